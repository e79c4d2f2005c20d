// `pindrag retarget CLIP --to CHARACTER -o OUT [--mapping MAP.json] [--report REPORT.json]`: a
// clip of one skeleton played by another character (animator/retarget.hpp), written as the other
// clip commands write, with a JSON report of the mapping, the contacts and the ranges.
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "animator/retarget.hpp"
#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "cli/json_fields.hpp"
#include "io/atomic_file.hpp"
#include "io/bundled_characters.hpp"

namespace cli {

namespace {

struct RetargetArgs {
  std::string clip, to, out, mapping, report;
};

// MAP.json: {"source joint": "target link" or null, ...}
std::vector<animator::MappingEntry> read_mapping(const std::string& path) {
  return animator::mapping_from_json(read_json_file(path), path);
}

nlohmann::json report_json(const animator::RetargetReport& r,
                           const core::Model& source,
                           const core::Model& target,
                           const core::Clip& clip) {
  nlohmann::json j;
  j["frames"] = clip.size();
  j["fps"] = 1.0 / clip.frame_time;
  j["source_convention"] = r.source_convention;
  j["target_convention"] = r.target_convention;
  nlohmann::json mapping = nlohmann::json::object();
  for (const auto& [s, t] : r.mapping) mapping[source.link_name[s]] = target.link_name[t];
  j["mapping"] = mapping;
  j["unmapped_source_joints"] = nlohmann::json::array();
  for (int s : r.unmapped_source) j["unmapped_source_joints"].push_back(source.link_name[s]);
  j["unmapped_target_links"] = nlohmann::json::array();
  for (int t : r.unmapped_target) j["unmapped_target_links"].push_back(target.link_name[t]);
  j["source_leg_length_m"] = r.source_leg_length;
  j["target_leg_length_m"] = r.target_leg_length;
  j["root_motion_scale"] = r.scale;
  j["source_floor_m"] = r.source_floor;
  nlohmann::json contacts = nlohmann::json::array();
  for (const animator::FootContact& c : r.contacts) {
    contacts.push_back({{"link", target.link_name[c.target_link]},
                        {"source_joint", source.link_name[c.source_link]},
                        {"first_frame", c.first},
                        {"last_frame", c.last},
                        {"slide_m", c.slide},
                        {"source_slide_m", c.source_slide}});
  }
  j["contacts"] = contacts;
  j["max_foot_slide_m"] = r.max_foot_slide;
  j["range_violation"] = {{"max", r.max_range_violation},
                          {"tolerance", animator::kRangeTolerance},
                          {"frames_out_of_range", r.frames_out_of_range}};
  j["max_effector_error_m"] = r.max_effector_error;
  return j;
}

void run_retarget(const RetargetArgs& a) {
  const auto out_format = clip_format(a.out);
  if (!out_format || !writable(*out_format)) {
    throw std::invalid_argument("-o: " + a.out +
                                " (rule: the extension must be .bvh, .gltf or .glb)");
  }
  const ClipFile source = read_clip_file(a.clip);
  const io::LoadResult character = io::load_character(a.to);
  animator::RetargetOptions options;
  if (!a.mapping.empty()) {
    options.mapping = read_mapping(a.mapping);
    options.mapping_origin = a.mapping;
  }
  animator::RetargetResult r =
      animator::retarget(*source.model, source.clip, *character.model, options);
  ClipFile out;
  out.model = character.model;
  write_clip_file(a.out, out, r.clip);
  if (!a.report.empty()) {
    const std::string text =
        report_json(r.report, *source.model, *character.model, r.clip).dump(2) + "\n";
    io::write_file_atomically(a.report, text);
  }
  for (const std::string& w : source.warnings) std::cerr << "warning: " << w << "\n";
  std::cerr << "pindrag retarget: " << a.out << ": " << r.clip.size() << " frames, "
            << r.report.mapping.size() << " joints mapped, " << r.report.contacts.size()
            << " foot contacts (largest slide " << r.report.max_foot_slide * 1000 << " mm), "
            << r.report.frames_out_of_range << " frames out of range\n";
}

}  // namespace

void add_retarget_command(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "retarget", "play a clip of one skeleton on another character (joints matched by name)");
  auto args = std::make_shared<RetargetArgs>();
  cmd->add_option("CLIP", args->clip, "input clip (.bvh, .gltf, .glb, .fbx, .dae)")->required();
  cmd->add_option("--to", args->to, "target character: human48, human34 or a character file")
      ->required();
  cmd->add_option("-o,--output", args->out, "output clip (.bvh, .gltf, .glb)")->required();
  cmd->add_option("--mapping", args->mapping,
                  "JSON object: source joint name -> target link name (or null), over the guesses");
  cmd->add_option("--report", args->report, "write a JSON report here");
  cmd->callback([args] {
    try {
      run_retarget(*args);
    } catch (const std::exception& e) {
      std::cerr << "pindrag retarget: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
