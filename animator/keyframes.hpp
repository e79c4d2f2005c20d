// Keyframes: poses at times, interpolated per key (step, linear, smooth). Rotations use slerp
// (linear) or squad (smooth) on the shortest path; 1-DOF coordinates and positions use linear or
// cubic Hermite (Catmull–Rom tangents) interpolation.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string_view>
#include <vector>

#include "core/model.hpp"

namespace animator {

enum class Interpolation { kStep, kLinear, kSmooth };
const char* to_string(Interpolation i);
std::optional<Interpolation> interpolation_from_string(std::string_view s);

struct Keyframe {
  double time = 0;
  Eigen::VectorXd q;                                     // nq
  Interpolation interpolation = Interpolation::kSmooth;  // how to leave this key toward the next
  bool operator==(const Keyframe& o) const {
    return time == o.time && q == o.q && interpolation == o.interpolation;
  }
};

/// Keys sorted by time, at most one per time.
class KeyTrack {
 public:
  /// Inserts a key, replacing one at the same time (within 1e-9 s). Returns its index.
  int insert(Keyframe key);
  bool remove(int index);
  /// Moves key `index` to a new time (replacing a key already there). Returns its new index.
  int move(int index, double time);
  /// Index of the key at this time (within tolerance), or -1.
  int find(double time, double tolerance = 1e-6) const;
  void clear() { keys_.clear(); }

  const std::vector<Keyframe>& keys() const { return keys_; }
  bool empty() const { return keys_.empty(); }
  double duration() const { return keys_.empty() ? 0.0 : keys_.back().time; }

  /// The pose at time t: the first key before the first, the last after the last.
  void sample(const core::Model& model, double t, Eigen::VectorXd& q_out) const;

  bool operator==(const KeyTrack& o) const { return keys_ == o.keys_; }

 private:
  std::vector<Keyframe> keys_;
};

}  // namespace animator
