#include <iostream>
#include <map>
#include <nlohmann/json.hpp>

#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "core/bounds.hpp"
#include "io/bundled_characters.hpp"

namespace cli {

namespace {

nlohmann::json character_summary(const core::Model& m, const std::vector<std::string>& warnings) {
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
  out["warnings"] = warnings;
  return out;
}

// a clip file: the character it animates and the clip (frames, timing, animated joints; for BVH
// the unit and which joints with position channels translate)
nlohmann::json clip_summary(const std::string& path) {
  const ClipFile f = read_clip_file(path);
  const core::Model& m = *f.model;
  nlohmann::json out = character_summary(m, f.warnings);
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

}  // namespace

void add_info_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("info",
                                 "print a JSON summary of a character file (or a bundled "
                                 "character name) or of a clip (.bvh, .gltf, .glb, .fbx, "
                                 ".dae)");
  auto file = std::make_shared<std::string>();
  cmd->add_option("FILE", *file, "character file (.urdf, .json), bundled name, or clip file")
      ->required();
  cmd->callback([file] {
    nlohmann::json out;
    try {
      if (clip_format(*file)) {
        out = clip_summary(*file);
      } else {
        const io::LoadResult loaded = io::load_character(*file);
        out = character_summary(*loaded.model, loaded.warnings);
      }
    } catch (const core::ModelError& e) {
      std::cerr << "pindrag info: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
    std::cout << out.dump(2) << "\n";
  });
}

}  // namespace cli
