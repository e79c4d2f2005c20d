// Keyframes: poses at times, interpolated per key (step, linear, smooth). Rotations use slerp
// (linear) or squad (smooth) on the shortest path; 1-DOF coordinates and positions use linear or
// cubic Hermite (Catmull–Rom tangents) interpolation.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
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

struct KeyChange;

/// Keys sorted by time, at most one per time. Copies share the keys until one of them changes
/// (copy on write), so a document holding a track is cheap to copy.
class KeyTrack {
 public:
  /// Inserts a key, replacing one at the same time (within 1e-9 s). Returns its index.
  int insert(Keyframe key);
  bool remove(int index);
  /// Moves key `index` to a new time (replacing a key already there). Returns its new index.
  int move(int index, double time);
  /// Index of the key at this time (within tolerance), or -1.
  int find(double time, double tolerance = 1e-6) const;
  void clear() { keys_ = empty_keys(); }

  const std::vector<Keyframe>& keys() const { return *keys_; }
  bool empty() const { return keys_->empty(); }
  int size() const { return static_cast<int>(keys_->size()); }
  double duration() const { return keys_->empty() ? 0.0 : keys_->back().time; }

  /// The pose at time t: the first key before the first, the last after the last.
  void sample(const core::Model& model, double t, Eigen::VectorXd& q_out) const;

  /// Applies a change made by diff_keys: forward removes its `removed` keys (matched by exact
  /// time) and inserts its `added` ones; backward the other way round.
  void apply(const KeyChange& change, bool forward);
  /// True when both share their keys (neither changed since one was copied from the other).
  bool shares_keys_with(const KeyTrack& o) const { return keys_ == o.keys_; }

  bool operator==(const KeyTrack& o) const { return keys_ == o.keys_ || *keys_ == *o.keys_; }

 private:
  using Keys = std::vector<Keyframe>;
  static std::shared_ptr<const Keys> empty_keys();
  std::shared_ptr<const Keys> keys_ = empty_keys();
};

/// The difference between two tracks: the keys only `before` has and the keys only `after` has
/// (a key changed in place is in both), each sorted by time.
struct KeyChange {
  std::vector<Keyframe> removed, added;
  bool empty() const { return removed.empty() && added.empty(); }
  /// Heap bytes the change holds (its keys and their configurations).
  std::size_t bytes() const;
};

/// What turns `before` into `after`; O(1) when they share their keys, O(keys) otherwise.
KeyChange diff_keys(const KeyTrack& before, const KeyTrack& after);
/// `first` followed by `second`, as one change.
KeyChange compose(const KeyChange& first, const KeyChange& second);

}  // namespace animator
