// Headless editing in motion (`pindrag edit`): a JSON script of edits, each a time window of the
// clip in which some links are moving pins (they follow the clip) while one link point is dragged
// along a trajectory. docs/edit-script.md describes the format.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "animator/session.hpp"
#include "core/model.hpp"
#include "ik/task.hpp"

namespace cli {

struct ScriptPin {
  int link = 0;
  ik::TaskMode mode = ik::TaskMode::kPose;
  core::Vector3 point = core::Vector3::Zero();  // link frame
};

struct DragKey {
  double time = 0;                                 // seconds of the clip
  core::Vector3 position = core::Vector3::Zero();  // offset from the clip's point, or world
};

struct ScriptDrag {
  int link = 0;
  core::Vector3 point = core::Vector3::Zero();  // link frame
  bool relative = true;       // keys are offsets from where the (layered) clip has the point
  std::vector<DragKey> keys;  // strictly increasing times; linear between, held beyond

  /// The key trajectory at time t (linear interpolation, clamped at both ends).
  core::Vector3 at(double t) const;
};

struct ScriptEdit {
  double start = 0, end = 0;  // seconds; the drag is held over the frames in (start, end]
  std::vector<ScriptPin> pins;
  ScriptDrag drag;
};

struct EditScript {
  double falloff = 0.25;  // seconds over which each edit fades in and out
  std::vector<ScriptEdit> edits;
};

/// Reads a script for `model` (link names resolved). Fields are named as JSON pointers.
/// @throws RequestError "<field>: <rule>"
EditScript parse_edit_script(const nlohmann::json& j, const core::Model& model);

/// Runs every edit on the session (whose clip is the motion to edit), in order; each becomes one
/// edit layer. @throws RequestError when an edit's window lies outside the clip
void run_edit_script(animator::Session& session, const EditScript& script);

}  // namespace cli
