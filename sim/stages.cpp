#include "sim/stages.hpp"

namespace sim {

const char* to_string(Stage s) {
  static constexpr std::array<const char*, kStageCount> kNames = {
      "kinematics",        "collision_search", "contact_forces",   "bias_forces", "mass_matrix",
      "operational_space", "forward_dynamics", "limit_projection", "integration"};
  return kNames[static_cast<int>(s)];
}

}  // namespace sim
