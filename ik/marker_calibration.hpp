// Subject calibration from a static (or any) range of frames, a simplified HeiMan/PUPPETEER
// scaling (Felis et al. §II, eq. 13 with p^c and p^m free): alternate
//   (a) fit the poses q_i of the calibration frames with the current model and offsets;
//   (b) re-estimate each marker offset as the mean of its measured positions in its link's frame,
//       p^m_j = (Σ_i X_W[link_j](q_i)⁻¹ m_ij + λ_j p^m_j,given) / (n_j + λ_j), the exact minimizer
//       of eq. 13 over p^m_j at fixed poses (a rigid motion keeps distances), with λ_j
//       pseudo-frames pulling a given offset toward the file's value (λ_j = 0 for offsets to be
//       estimated);
//   (c) re-estimate the segment scales s_k (every joint placement below link k is scaled by s_k)
//       by linear least squares at fixed poses: ∂r^M_j/∂s_k = R_W[k] p_k,c for each child joint c
//       of k on the path to marker j, p_k,c being the unscaled placement of c in k; a ridge pulls
//       s_k toward 1 so segments the markers do not see keep their length.
#pragma once

#include <memory>
#include <vector>

#include "core/model.hpp"
#include "ik/marker_fit.hpp"
#include "ik/marker_set.hpp"

namespace ik {

struct CalibrationSettings {
  int first_frame = 0;  // calibration range [first_frame, last_frame)
  int last_frame = -1;  // -1: one second from the first frame at or after first_frame that has
                        // enough markers (at least one frame)
  int max_frames = 40;  // frames of the range used (evenly spaced)
  // Alternations of (a), (b) and (c): until a round lowers the calibration frames' marker RMS by
  // less than rms_tolerance of itself, at most max_rounds. The alternation creeps along the
  // directions in which a link's offsets and its pose turn together, so it takes tens of rounds.
  int max_rounds = 100;
  double rms_tolerance = 1e-3;
  double offset_prior = 2.0;           // λ for given offsets, in frames
  bool estimate_given_offsets = true;  // false: only offsets left out of the marker set move
  bool estimate_scales = true;
  double scale_prior = 1e-3;  // ridge (m²) pulling every scale toward 1
  double min_scale = 0.7;     // scales are kept inside [min_scale, max_scale]
  double max_scale = 1.4;
};

struct CalibrationResult {
  std::shared_ptr<const core::Model> model;  // the model with the scaled joint placements
  MarkerSet set;                             // with the estimated offsets
  std::vector<double> scales;                // per link (njoints; 1 for unscaled links)
  std::vector<double> rms_per_round;         // marker RMS over the calibration frames (m)
  int frames_used = 0;
};

/// Calibrates offsets (and segment scales) on `trajectories` (markers in the order of `set`).
/// Frames of the range with fewer than fit.min_markers present markers are skipped.
/// @throws std::invalid_argument when the range holds no usable frame
CalibrationResult calibrate_markers(std::shared_ptr<const core::Model> model,
                                    const MarkerSet& set,
                                    const MarkerTrajectories& trajectories,
                                    const MarkerFitSettings& fit = {},
                                    const CalibrationSettings& settings = {});

/// `model` with the joint placements X_PJ[c].p of the children c of each link k multiplied by
/// scales[k] (njoints entries). Geometry and inertia are kept.
std::shared_ptr<const core::Model> scale_joint_placements(const core::Model& model,
                                                          const std::vector<double>& scales);

}  // namespace ik
