// Marker sets and marker trials for fitting (docs/marker-fitting.md), shared by `pindrag fit` and
// the server's C3D upload:
//   - marker set documents {"markers": {"LASI": {"link": "pelvis", "offset": [x, y, z],
//     "weight": 1}, ...}}; "offset" (metres, link frame) may be left out: it is then estimated
//     by the calibration and starts at the link origin; unknown keys are warned about;
//   - a C3D trial turned into the trajectories of a marker set: columns in the set's order,
//     matched by label (the subject prefix already stripped by io/c3d.hpp), lab axes turned into
//     pindrag's world by ik::lab_to_world (Z up → Y up).
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "animator/clip_markers.hpp"
#include "core/clip.hpp"
#include "core/model.hpp"
#include "ik/marker_fit.hpp"
#include "ik/marker_set.hpp"
#include "io/c3d.hpp"

namespace animator {

/// A marker set or trial that cannot be used; what() names the field and the rule.
class MarkerSetError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The marker set described by `doc` on `model`'s links; `warn` receives "<field>: <what>" for
/// keys it does not know.
/// @throws MarkerSetError "<field>: <rule>", e.g. "/markers/LASI/link: no link 'pelvs' in human48"
ik::MarkerSet parse_marker_set(const nlohmann::json& doc,
                               const core::Model& model,
                               const std::function<void(const std::string&)>& warn = {});

/// The bundled marker set for the model (characters/markers/cmu41_<model name>.json), or ""
/// when there is none.
std::string bundled_marker_set_path(const core::Model& model);

struct TrialMarkers {
  ik::MarkerTrajectories trajectories;
  std::vector<std::string> not_in_trial;  // markers of the set the trial lacks (always missing)
  std::vector<std::string> unused;        // trial labels the set does not name
};

/// @throws MarkerSetError when no marker of the set is in the trial
TrialMarkers markers_from_c3d(const io::C3dTrial& trial, const ik::MarkerSet& set);

/// Fits a trial onto `model` with its bundled marker set: offsets calibrated on the first second
/// in which the subject is seen, the model's proportions kept (no segment scaling: the clip is
/// for this very character), every frame fitted inside the joint ranges.
/// @throws MarkerSetError when the model has no bundled marker set (human48, human34) or the
///         trial has none of its markers
struct FittedTrial {
  core::Clip clip;                             // one configuration of the model per frame
  std::shared_ptr<const ClipMarkers> markers;  // the trial's markers of the set, calibrated
};
FittedTrial fit_trial(const io::C3dTrial& trial, const core::Model& model);

}  // namespace animator
