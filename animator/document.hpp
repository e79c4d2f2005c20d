// The document of a session: everything an edit can change, what undo restores and what a saved
// session holds. Copies are cheap: clips and layers are shared, immutable.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "animator/clip_markers.hpp"
#include "animator/edit_layer.hpp"
#include "animator/keyframes.hpp"
#include "animator/pin.hpp"
#include "core/clip.hpp"
#include "ik/solver.hpp"
#include "sim/scene.hpp"

namespace animator {

/// Seconds over which an edit made during playback fades in and out.
constexpr double kDefaultEditFalloff = 0.5;

struct Document {
  Eigen::VectorXd q;
  std::vector<Pin> pins;
  KeyTrack keys;
  std::shared_ptr<const core::Clip> clip;
  std::shared_ptr<const ClipMarkers> markers;  // of the trial the clip was fitted to, else null
  LayerStack layers;
  ik::SolverSettings settings;
  sim::Scene scene;  // the effects it simulates
  double edit_falloff = kDefaultEditFalloff;
};

}  // namespace animator
