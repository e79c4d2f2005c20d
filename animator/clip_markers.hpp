// The measured markers of the trial a clip was fitted to, kept beside the clip: the page draws
// each measured marker with its residual line to the model's virtual marker, so an animator sees
// how far the fit, and every edit made since, takes the figure from the capture. Shared and
// immutable like the clip; undo, the journal and the session file carry it with the clip.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "ik/marker_fit.hpp"
#include "ik/marker_set.hpp"

namespace animator {

struct ClipMarkers {
  ik::MarkerSet set;                // names, links and (calibrated) offsets of the virtual markers
  ik::MarkerTrajectories measured;  // world frame, one row per clip frame, in the set's order
  /// Distinct for every ClipMarkers made: what a client compares to know it holds these.
  std::uint64_t revision = 0;
};

/// Markers that pass check_clip_markers for `model`, with a fresh revision.
/// @throws std::invalid_argument whose what() is the rule broken
std::shared_ptr<const ClipMarkers> make_clip_markers(const core::Model& model,
                                                     ik::MarkerSet set,
                                                     ik::MarkerTrajectories measured);

/// Empty when the set is valid for `model` (ik::check_marker_set), has at least one marker, and
/// `measured` has one column per marker, a positive rate, at least one frame, and finite
/// positions where present; else the first rule broken.
std::string check_clip_markers(const core::Model& model,
                               const ik::MarkerSet& set,
                               const ik::MarkerTrajectories& measured);

/// Empty when `markers` can ride on `clip`: one measured row per frame, at the clip's rate
/// (to 1e-9 relative); else the rule broken.
std::string check_markers_fit_clip(const ClipMarkers& markers, const core::Clip& clip);

}  // namespace animator
