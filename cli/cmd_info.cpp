#include <cmath>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>

#include "animator/facing.hpp"
#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "core/bounds.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "io/bundled_characters.hpp"
#include "io/c3d.hpp"
#include "io/read_file.hpp"

namespace cli {

namespace {

// which way the figure faces in pose `q` and the links that tell it (the page turns it to face
// +Z when it opens: animator/facing.hpp); null when nothing tells
nlohmann::json facing_summary(const core::Model& m, const Eigen::VectorXd& q) {
  core::Data data(m);
  core::forward_kinematics(m, data, q);
  const auto facing = animator::facing_of(m, data);
  if (!facing) return nullptr;
  nlohmann::json from = nlohmann::json::array();
  for (const auto& [a, b] : facing->links) from.push_back({m.link_name[a], m.link_name[b]});
  const core::Vector3& d = facing->direction;
  return {{"direction", {d.x(), 0.0, d.z()}},
          {"degrees_from_plus_z", std::atan2(d.x(), d.z()) * 180 / std::numbers::pi},
          {"by", facing->by_toes ? "toes" : "left and right"},
          {"from", from}};
}

// `pose`: where the facing is read (the rest configuration, or where a clip starts)
nlohmann::json character_summary(const core::Model& m,
                                 const std::vector<std::string>& warnings,
                                 const Eigen::VectorXd& pose) {
  std::map<std::string, int> by_type;
  for (int i = 1; i < m.njoints; ++i) ++by_type[core::to_string(m.joint_type[i])];
  nlohmann::json out;
  out["name"] = m.name;
  out["links"] = m.nlinks();
  out["joints"] = by_type;
  out["nq"] = m.nq;
  out["nv"] = m.nv;
  out["total_mass"] = m.total_mass();
  out["height"] = core::neutral_height(m);
  out["root"] = m.link_name[1];
  out["root_joint"] = core::to_string(m.joint_type[1]);
  out["facing"] = facing_summary(m, pose);
  out["warnings"] = warnings;
  return out;
}

// a clip file: the character it animates and the clip (frames, timing, animated joints; for BVH
// the unit and which joints with position channels translate)
nlohmann::json clip_summary(const std::string& path) {
  const ClipFile f = read_clip_file(path);
  const core::Model& m = *f.model;
  // facing where the clip starts, as the page shows it
  nlohmann::json out = character_summary(
      m, f.warnings, f.clip.size() > 0 ? f.clip.frames.front() : core::rest_configuration(m));
  int moving = 0;
  for (int i = 1; i < m.njoints; ++i) moving += m.joint_type[i] != core::JointType::kFixed;
  nlohmann::json clip;
  clip["frames"] = f.clip.size();
  clip["frame_time"] = f.clip.frame_time;
  clip["fps"] = 1.0 / f.clip.frame_time;
  clip["duration"] = f.clip.duration();
  clip["joints"] = f.bvh_layout ? static_cast<int>(f.bvh_layout->joints.size()) : moving;
  if (f.bvh_layout) {
    clip["unit"] = f.unit;
    // non-root joints with position channels: constant ones import as rotational joints at that
    // offset, moving ones as free joints (io/bvh_import.hpp)
    const io::BvhTranslationJoints moved = io::bvh_translation_joints(m, *f.bvh_layout);
    clip["constant_translations"] = moved.constant;
    clip["translating_joints"] = moved.translating;
  }
  if (!f.clip_name.empty()) clip["name"] = f.clip_name;
  if (f.clips_in_file != 1) clip["animations_in_file"] = f.clips_in_file;
  if (f.skin && !f.skin->empty()) {
    clip["skin"] = {{"vertices", f.skin->positions.size()},
                    {"triangles", f.skin->triangles.size()},
                    {"bones", f.skin->bones.size()}};
  }
  out["clip"] = clip;
  return out;
}

// a marker trial: timing, units, and each label with the fraction of frames it is missing from
nlohmann::json c3d_summary(const std::string& path) {
  const io::C3dTrial t = io::read_c3d(path);
  nlohmann::json out;
  out["subject"] = t.subject;
  out["frames"] = t.frame_count();
  out["rate_hz"] = t.rate_hz;
  out["duration"] = t.frame_count() > 0 ? t.time(t.frame_count() - 1) : 0.0;
  out["units"] = t.units;
  out["points"] = t.point_count();
  out["missing_fraction"] = t.missing_fraction();
  nlohmann::json labels = nlohmann::json::object();
  for (int p = 0; p < t.point_count(); ++p) {
    int missing = 0;
    for (int f = 0; f < t.frame_count(); ++f) missing += !t.is_present(f, p);
    labels[t.labels[p]] = {
        {"missing", t.frame_count() > 0 ? static_cast<double>(missing) / t.frame_count() : 0.0}};
  }
  out["labels"] = labels;
  out["warnings"] = t.warnings;
  return out;
}

// every kind of file the command summarizes, for the message that refuses another
constexpr const char* kReads =
    "pindrag info reads .urdf and .json characters, .bvh, .gltf, .glb, .fbx and .dae clips, .c3d "
    "marker trials, and the bundled characters by name";

}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("info",
                                 "print a JSON summary of a character file (or a bundled "
                                 "character name), of a clip (.bvh, .gltf, .glb, .fbx, "
                                 ".dae) or of a marker trial (.c3d)");
  auto file = std::make_shared<std::string>();
  cmd->add_option("FILE", *file,
                  "character file (.urdf, .json), bundled name, clip file, or marker trial")
      ->required();
  cmd->callback([file] {
    nlohmann::json out;
    try {
      if (lower_extension(*file) == ".c3d") {
        out = c3d_summary(*file);
      } else if (clip_format(*file)) {
        out = clip_summary(*file);
      } else if (const std::string ext = lower_extension(*file);
                 !ext.empty() && ext != ".urdf" && ext != ".json") {
        // io::load_character's own rule names character files alone; this command reads more
        throw core::ModelError(
            {*file + ": unknown file type '" + ext + "' (rule: " + kReads + ")"});
      } else {
        const io::LoadResult loaded = io::load_character(*file);
        out = character_summary(*loaded.model, loaded.warnings,
                                core::rest_configuration(*loaded.model));
      }
    } catch (const core::ModelError& e) {
      std::cerr << "pindrag info: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    } catch (const io::C3dError& e) {
      std::cerr << "pindrag info: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    } catch (const io::FileError& e) {
      std::cerr << "pindrag info: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
    std::cout << out.dump(2) << "\n";
  });
}

}  // namespace cli
