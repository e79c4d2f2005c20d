// Props: rigid boxes, spheres and capsules, each a one-link model with a free joint, solid and of
// uniform density. Capsules run along their link's z axis, as every capsule of a Model does.
#pragma once

#include <memory>
#include <string>

#include "core/model.hpp"

namespace sim {

struct PropShape {
  core::Geometry::Shape shape = core::Geometry::Shape::kBox;
  core::Vector3 size{0.1, 0.1, 0.1};  // box: full extents (m)
  double radius = 0.05;               // sphere and capsule (m)
  double length = 0.1;                // capsule: distance between its end-sphere centres (m)
};

/// A one-link model named `name` with a free joint at the prop's centre of mass.
/// @throws core::ModelError naming the prop and the rule (mass or a size not finite and > 0,
///         a shape that is not a box, sphere or capsule)
std::shared_ptr<const core::Model> make_prop(const std::string& name,
                                             const PropShape& shape,
                                             double mass);

}  // namespace sim
