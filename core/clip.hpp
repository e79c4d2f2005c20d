// Clips: motions as fixed-rate sequences of configurations of one model.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/model.hpp"

namespace core {

struct Clip {
  double frame_time = 1.0 / 30.0;       // seconds per frame (> 0)
  std::vector<Eigen::VectorXd> frames;  // configurations, nq each

  int size() const { return static_cast<int>(frames.size()); }
  bool empty() const { return frames.empty(); }
  /// Time of the last frame (0 for fewer than two frames).
  double duration() const { return frames.size() < 2 ? 0.0 : (frames.size() - 1) * frame_time; }
  bool operator==(const Clip& o) const { return frame_time == o.frame_time && frames == o.frames; }
};

/// q0 ⊕ s (q1 ⊖ q0): linear in 1-DOF coordinates and positions, slerp on rotations (the shortest
/// way). s = 0 gives q0 exactly and s = 1 gives q1 (up to the quaternion sign).
void interpolate(const Model& model,
                 const Eigen::VectorXd& q0,
                 const Eigen::VectorXd& q1,
                 double s,
                 Eigen::VectorXd& q_out);

/// The clip's configuration at time t (clamped to [0, duration]), interpolated between frames.
/// Frames are returned bit-exactly at their own times.
void sample(const Model& model, const Clip& clip, double t, Eigen::VectorXd& q_out);

/// The clip's velocity at time t (nv), by central differences of neighbouring frames on the
/// manifold (one-sided at the ends; zero for a single frame).
void sample_velocity(const Model& model, const Clip& clip, double t, Eigen::VectorXd& v_out);

/// Empty when every frame has the model's nq, finite values and unit quaternions and the frame
/// time is positive and finite; otherwise a message naming the first bad frame.
std::string check_clip(const Model& model, const Clip& clip);

}  // namespace core
