// The stages of one physics step, in the order they run, with a call counter per stage. The
// world runs only the stages its scene's effects need (MuJoCo's mj_forwardSkip and mjDSBL_*
// flags are the model); the counters prove it. Beside the counters, a wall clock per part of the
// step says what each effect costs (the page shows it next to the effect's switch).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>

#include "sim/scene.hpp"

namespace sim {

enum class Stage {
  kKinematics,        // link poses and velocities (and J̇v) for the current state
  kCollisionSearch,   // broad phase (bounding spheres) and narrow phase: contact points
  kContactForces,     // penalty and friction forces at the points, and their derivatives
  kBiasForces,        // b(q, v) by RNEA: Coriolis, centrifugal and gravity terms
  kMassMatrix,        // H(q) by CRBA and its tree-sparse factorization
  kOperationalSpace,  // Φ = J H⁻¹ Jᵀ of the contact handles (the implicit contact solve)
  kForwardDynamics,   // joint accelerations
  kLimitProjection,   // hard joint limits: impulses that stop joints at their limits
  kIntegration,       // (q, v) advanced by one step on the configuration manifold
};
constexpr int kStageCount = 9;

/// "kinematics", "collision_search", ...
const char* to_string(Stage s);

/// The parts of a step the wall clock times, each the work of one effect (or shared).
enum class TimedPart {
  kKinematics,     // link poses for the contact search and the pins (shared)
  kGroundSearch,   // contact points against the ground and the static boxes
  kSelfSearch,     // contact points between the links of one body
  kContactForces,  // penalty and friction forces, the implicit contact solve
  kDynamicPins,    // the acceleration-level solve of the pins and the drag
  kDynamics,       // forward dynamics of the bodies the pins do not drive (gravity's cost)
  kLimits,         // hard-limit projection
  kIntegration,    // (q, v) advanced (shared)
};
constexpr int kTimedPartCount = 8;

/// Accumulated wall-clock time per timed part (one steady_clock read per part and step).
struct StageTimers {
  std::array<std::chrono::nanoseconds, kTimedPartCount> time{};

  void add(TimedPart p, std::chrono::nanoseconds d) { time[static_cast<int>(p)] += d; }
  std::chrono::nanoseconds operator[](TimedPart p) const { return time[static_cast<int>(p)]; }
  void reset() { time.fill(std::chrono::nanoseconds::zero()); }
};

/// Seconds of `t` spent for effect e: gravity the dynamics and integration, ground_contact the
/// kinematics, ground search and contact forces, self_collision its search, hard_limits the
/// projection, dynamic_pins the pins' solve; friction shapes the contact forces and has none.
double effect_seconds(const StageTimers& t, Effect e);

/// Times consecutive parts of one step: lap(p) charges p with the time since the previous lap.
class StageClock {
 public:
  explicit StageClock(StageTimers& timers)
      : timers_(timers), last_(std::chrono::steady_clock::now()) {}
  void lap(TimedPart p) {
    const auto now = std::chrono::steady_clock::now();
    timers_.add(p, now - last_);
    last_ = now;
  }
  /// Starts the next lap now, charging nobody with the time since the last (timed elsewhere).
  void skip() { last_ = std::chrono::steady_clock::now(); }

 private:
  StageTimers& timers_;
  std::chrono::steady_clock::time_point last_;
};

struct StageCounters {
  std::array<std::uint64_t, kStageCount> calls{};
  StageTimers timers;  // wall-clock time per part since the last reset

  void count(Stage s) { ++calls[static_cast<int>(s)]; }
  std::uint64_t operator[](Stage s) const { return calls[static_cast<int>(s)]; }
  void reset() {
    calls.fill(0);
    timers.reset();
  }
};

}  // namespace sim
