// From a C3D trial to the marker trajectories of a marker set (ik/marker_fit.hpp): columns in
// the set's order, matched by label (the subject prefix already stripped by io/c3d.hpp), lab
// axes turned into pindrag's world by ik::lab_to_world (Z up → Y up).
#pragma once

#include <string>
#include <vector>

#include "ik/marker_fit.hpp"
#include "ik/marker_set.hpp"
#include "io/c3d.hpp"

namespace cli {

struct TrialMarkers {
  ik::MarkerTrajectories trajectories;
  std::vector<std::string> not_in_trial;  // markers of the set the trial lacks (always missing)
  std::vector<std::string> unused;        // trial labels the set does not name
};

/// @throws RequestError when no marker of the set is in the trial
TrialMarkers markers_from_c3d(const io::C3dTrial& trial, const ik::MarkerSet& set);

}  // namespace cli
