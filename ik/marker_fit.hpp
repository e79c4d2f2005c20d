// Marker fitting (Felis et al. eq. 13–14, digest §2.16): per frame, the configuration q that
// minimizes ½ Σ_j w_j |m_j − r^M_j(q)|² over the markers j present in the frame, where m_j is the
// recorded marker and r^M_j(q) = X_W[link_j](q) · offset_j the model's virtual marker.
//
// Each frame is solved by ik::Solver with one position pin per marker on its link (level 3, SR
// inverse with Sugihara's residual damping) and the joint ranges above them (level 2): with the
// pin gain K = 1 and one step of h = 1, a solver step is the damped Gauss–Newton step
// Δq = J^*(m − r^M(q)) (PUPPETEER's "Sugihara LM"), repeated until max |Δq| < tolerance.
// Frames are warm-started from the previous frame; the first fitted frame starts from the rest
// pose with its root placed on the markers (place_root). Missing markers get weight 0. A frame
// with too few markers is not fitted: it continues the previous frames' velocity and is flagged.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/clip.hpp"
#include "core/data.hpp"
#include "core/model.hpp"
#include "ik/marker_set.hpp"
#include "ik/problem.hpp"
#include "ik/solver.hpp"

namespace ik {

/// Motion-capture labs are usually Z up (C3D); pindrag's world is Y up with +Z forward. The map
/// (x, y, z)_lab → (x, z, −y)_world is a rotation of −90° about x (determinant +1), so handedness
/// is kept: lab Z becomes world Y, and a subject facing lab −Y faces world +Z.
inline core::Vector3 lab_to_world(const core::Vector3& p_Lab) {
  return {p_Lab.x(), p_Lab.z(), -p_Lab.y()};
}

/// Marker trajectories in the world frame (Y up, metres), column m being marker m of a marker
/// set. Samples are frame-major: sample (f, m) is at index f × markers + m.
struct MarkerTrajectories {
  double rate_hz = 0;
  int frames = 0;
  int markers = 0;
  std::vector<core::Vector3> positions;  // zero where missing
  std::vector<std::uint8_t> present;     // 1 measured, 0 missing

  const core::Vector3* frame_positions(int f) const { return positions.data() + f * markers; }
  const std::uint8_t* frame_present(int f) const { return present.data() + f * markers; }
};

struct MarkerFitSettings {
  int max_iterations = 10;           // Gauss–Newton steps per frame
  int first_frame_iterations = 80;   // steps for a frame that starts from the rest pose
  double tolerance = 1e-4;           // stop when an iteration moves no coordinate more (rad or m)
  int min_markers = 6;               // fewer present markers: the frame is extrapolated, flagged
  int min_root_markers = 1;          // fewer present markers on the root link: likewise
  double damping = kDefaultDamping;  // SR inverse k at residuals of 1 m (Sugihara schedule)
  bool enforce_ranges = true;
  bool predict = true;  // warm-start from the previous pose moved on by the last velocity
  // weight of a pull toward the rest posture on every joint below the root: keeps joints the
  // markers do not see (a spine or neck without markers, a toe) from drifting (0: none)
  double reference_weight = 0.0;
  // inside the joint ranges, a frame fitted with an RMS marker error above restart_rms (m) is
  // fitted once more from another start: its warm start fitted without the ranges, then brought
  // inside them. The better of the two fits is kept. After a fast, extreme movement (a kick above
  // the head, a handstand) the warm start can stay trapped on the wrong side of a range, a leg
  // a metre off; the unbounded fit finds where the limbs are and the ranges then hold them at
  // their nearest admissible pose (0: never)
  double restart_rms = 0.04;
  // fit_trajectories: threads that fit a long trial in contiguous chunks (0: one per core). A
  // chunk starts chunk_lead_in frames early, from the rest pose placed on the markers, and keeps
  // only its own frames, so each of them is warm-started as in a single pass. A chunk whose first
  // frame is not the fit the chunk before it reaches there (inside the ranges a lead-in can
  // settle on another solution) is fitted again from that chunk's end.
  int threads = 1;
  int chunk_lead_in = 30;  // frames fitted before a chunk's first one and discarded (warm-up)
};
/// Fewest frames per thread worth a chunk of its own.
constexpr int kMinChunkFrames = 200;

/// Empty when usable, else a message naming the first bad field.
std::string validate(const MarkerFitSettings& s);

struct FrameFit {
  double rms = 0;        // root-mean-square marker error over the present markers (m)
  int present = 0;       // markers present in the frame
  int iterations = 0;    // solver steps taken
  bool flagged = false;  // too few markers: extrapolated from the previous frames
  // the frame was fitted a second time from its unbounded fit (MarkerFitSettings::restart_rms),
  // and whether that fit was the better one and kept
  bool second_start = false;
  bool second_start_kept = false;
};

/// Fits frames one at a time; holds the solver, its problem and the kinematics workspace, so
/// fitting a frame allocates nothing once the first frame has been fitted.
class MarkerFitter {
 public:
  /// @throws std::invalid_argument when the marker set or the settings are unusable
  MarkerFitter(const core::Model& model, const MarkerSet& set, const MarkerFitSettings& s = {});

  /// Moves the root of q rigidly so that the model's markers best match the present targets
  /// (Kabsch): the root-link markers when 3 or more are present, else all present markers.
  void place_root(const core::Vector3* targets, const std::uint8_t* present, Eigen::VectorXd& q);
  /// Fits q (warm start, updated in place) to one frame's targets with at most `iterations`
  /// solver steps. Fills errors(). Does not check min_markers (see fit_trajectories).
  FrameFit fit(const core::Vector3* targets,
               const std::uint8_t* present,
               Eigen::VectorXd& q,
               int iterations);
  /// Marker errors |m_j − r^M_j(q)| of the last fit (m); 0 for missing markers.
  const Eigen::VectorXd& errors() const { return errors_; }
  /// Number of present markers, and of those on the root link.
  int count_present(const std::uint8_t* present) const;
  int count_root_present(const std::uint8_t* present) const;
  /// Replaces a marker's offset (link frame) for later fits.
  void set_offset(int marker, const core::Vector3& offset);
  const MarkerSet& marker_set() const { return set_; }
  const MarkerFitSettings& settings() const { return settings_; }
  /// Kinematics at the last fitted q.
  const core::Data& data() const { return data_; }

 private:
  void compute_errors(const core::Vector3* targets, const std::uint8_t* present);

  const core::Model& model_;
  MarkerSet set_;
  MarkerFitSettings settings_;
  core::Data data_;
  Problem problem_;
  Solver solver_;
  Eigen::VectorXd errors_;
};

/// Error statistics of one marker over a trial (frames where it is present and fitted).
struct MarkerStats {
  double mean = 0;  // m
  double max = 0;   // m
  int missing = 0;  // frames without the marker
};

struct MarkerFitResult {
  core::Clip clip;                   // one configuration per frame, at the trial's rate
  std::vector<FrameFit> frames;      // per frame
  std::vector<MarkerStats> markers;  // per marker of the set
  double mean_error = 0;             // mean over all fitted samples (m)
  double microseconds_per_frame = 0;
  int refitted_chunks = 0;  // chunks fitted again from the end of the one before (threads > 1)
};

/// Fits every frame of `trajectories` (markers in the order of the set), warm-starting each
/// from the previous one; with settings.threads other than 1, in chunks on several threads.
/// `progress` (optional, called on the calling thread) receives the fraction done.
MarkerFitResult fit_trajectories(const core::Model& model,
                                 const MarkerSet& set,
                                 const MarkerTrajectories& trajectories,
                                 const MarkerFitSettings& settings = {},
                                 const std::function<void(double)>& progress = {});

}  // namespace ik
