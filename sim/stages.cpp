#include "sim/stages.hpp"

namespace sim {

const char* to_string(Stage s) {
  static constexpr std::array<const char*, kStageCount> kNames = {
      "kinematics",        "collision_search", "contact_forces",   "bias_forces", "mass_matrix",
      "operational_space", "forward_dynamics", "limit_projection", "integration"};
  return kNames[static_cast<int>(s)];
}

double effect_seconds(const StageTimers& t, Effect e) {
  using P = TimedPart;
  std::chrono::nanoseconds d{};
  switch (e) {
    case Effect::kGravity:
      d = t[P::kDynamics] + t[P::kIntegration];
      break;
    case Effect::kGroundContact:
      d = t[P::kKinematics] + t[P::kGroundSearch] + t[P::kContactForces];
      break;
    case Effect::kSelfCollision:
      d = t[P::kSelfSearch];
      break;
    case Effect::kHardLimits:
      d = t[P::kLimits];
      break;
    case Effect::kDynamicPins:
      d = t[P::kDynamicPins];
      break;
    case Effect::kFriction:
      break;
  }
  return std::chrono::duration<double>(d).count();
}

}  // namespace sim
