// `pindrag edit CLIP --script edits.json -o OUT`: editing in motion without a user: the script's
// pins and drag trajectories are played through an animator::Session and the edited motion is
// written (docs/edit-script.md).
#include <iostream>
#include <limits>

#include "animator/session.hpp"
#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "cli/edit_script.hpp"
#include "cli/json_fields.hpp"

namespace cli {

namespace {

struct EditArgs {
  std::string clip, script, out;
};

// Batch work on a file the operator chose: the clip and its edits are bounded by the file and
// the script, not by the server's per-session budgets (animator/limits.hpp).
animator::Limits batch_limits() {
  animator::Limits l;
  l.max_clip_seconds = 1e12;
  l.max_clip_frames = std::numeric_limits<std::int64_t>::max();
  l.max_clip_values = std::numeric_limits<std::int64_t>::max();
  l.max_layers = std::numeric_limits<int>::max();
  return l;
}

void edit(const EditArgs& a) {
  const auto out_format = clip_format(a.out);
  if (!out_format || !writable(*out_format)) {
    throw std::invalid_argument("-o: " + a.out +
                                " (rule: the extension must be .bvh, .gltf or .glb)");
  }
  ClipFile source = read_clip_file(a.clip);
  EditScript script;
  try {
    script = parse_edit_script(read_json_file(a.script), *source.model);
  } catch (const RequestError& e) {
    throw RequestError(a.script + ": " + e.what());
  }
  animator::Session session(source.model, source.model->name);
  session.set_limits(batch_limits());
  session.set_clip(source.clip);
  try {
    run_edit_script(session, script);
  } catch (const std::runtime_error& e) {
    throw RequestError(a.script + ": " + e.what());
  }
  const core::Clip edited = session.animation_clip();
  write_clip_file(a.out, source, edited);
  for (const std::string& w : source.warnings) std::cerr << "warning: " << w << "\n";
  std::cerr << "pindrag edit: " << a.out << ": " << script.edits.size() << " edits over "
            << edited.size() << " frames\n";
}

}  // namespace

void add_edit_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("edit",
                                 "edit a clip in motion from a script of pins and drag "
                                 "trajectories (docs/edit-script.md)");
  auto args = std::make_shared<EditArgs>();
  cmd->add_option("CLIP", args->clip, "clip to edit (.bvh, .gltf, .glb, .fbx, .dae)")->required();
  cmd->add_option("--script", args->script, "edit script (JSON)")->required();
  cmd->add_option("-o,--output", args->out, "edited clip (.bvh, .gltf, .glb)")->required();
  cmd->callback([args] {
    try {
      edit(*args);
    } catch (const std::exception& e) {
      std::cerr << "pindrag edit: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
