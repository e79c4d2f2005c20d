// The stages of one physics step, in the order they run, with a call counter per stage. The
// world runs only the stages its scene's effects need (MuJoCo's mj_forwardSkip and mjDSBL_*
// flags are the model); the counters prove it.
#pragma once

#include <array>
#include <cstdint>

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

struct StageCounters {
  std::array<std::uint64_t, kStageCount> calls{};

  void count(Stage s) { ++calls[static_cast<int>(s)]; }
  std::uint64_t operator[](Stage s) const { return calls[static_cast<int>(s)]; }
  void reset() { calls.fill(0); }
};

}  // namespace sim
