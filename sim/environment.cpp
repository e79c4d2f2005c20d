#include "sim/environment.hpp"

#include <cmath>

namespace sim {

std::string validate(const Environment& e) {
  if (!e.ground.normal.allFinite() || std::abs(e.ground.normal.norm() - 1.0) > 1e-6) {
    return "ground.normal: must be a finite unit vector";
  }
  if (!e.ground.point.allFinite()) return "ground.point: must be finite";
  for (size_t k = 0; k < e.boxes.size(); ++k) {
    const StaticBox& b = e.boxes[k];
    const std::string at = "boxes[" + std::to_string(k) + "]";
    if (!b.pose.p.allFinite() || !b.pose.R.allFinite() ||
        !(b.pose.R.transpose() * b.pose.R).isIdentity(1e-6) || b.pose.R.determinant() < 0) {
      return at + ".pose: must be a finite rigid transform";
    }
    if (!b.half_extents.allFinite() || (b.half_extents.array() <= 0).any()) {
      return at + ".size: every extent must be a finite number > 0";
    }
  }
  return {};
}

}  // namespace sim
