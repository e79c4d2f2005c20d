// The static environment of a world: a ground plane of any orientation (so slopes) and boxes
// that never move.
#pragma once

#include <string>
#include <vector>

#include "core/spatial.hpp"

namespace sim {

/// The half space below the plane n · (p − point) < 0 is solid.
struct GroundPlane {
  core::Vector3 normal{0, 1, 0};  // unit, pointing out of the ground
  core::Vector3 point{0, 0, 0};
  bool operator==(const GroundPlane&) const = default;
};

struct StaticBox {
  core::Transform pose;  // box frame in the world; the box is centred on its origin
  core::Vector3 half_extents{1, 1, 1};
  bool operator==(const StaticBox&) const = default;
};

struct Environment {
  GroundPlane ground;
  std::vector<StaticBox> boxes;
  bool operator==(const Environment&) const = default;
};

/// Empty when usable, else a message naming the first bad field ("ground.normal: ...").
std::string validate(const Environment& e);

}  // namespace sim
