// The collision shapes of a body, cached once per model in a form the contact search reads fast:
// spheres, capsules and boxes in link frames, and one bounding sphere per link for the broad
// phase. Cylinders are treated as capsules of the same radius that fit inside them lengthwise;
// meshes do not collide (their link keeps its other shapes).
#pragma once

#include <utility>
#include <vector>

#include "core/model.hpp"

namespace sim {

struct LinkShape {
  enum class Kind { kSphere, kCapsule, kBox };
  Kind kind = Kind::kSphere;
  int index = 0;                // index in Model::collision[link]
  core::Transform X_LinkShape;  // capsules run along the shape frame's z axis
  double radius = 0;            // sphere, capsule
  double half_length = 0;       // capsule: half the distance between its sphere centres
  core::Vector3 half_extents = core::Vector3::Zero();  // box
};

struct LinkBound {
  core::Vector3 center_Link = core::Vector3::Zero();
  double radius = -1;  // < 0: the link has no collision shape
};

struct BodyShapes {
  std::vector<std::vector<LinkShape>> shapes;  // per link (njoints; entry 0 empty)
  std::vector<LinkBound> bounds;               // per link
  /// Link pairs that may collide with each other: not parent and child, and not already
  /// touching in the configuration the shapes were built for (shapes that overlap at rest, as a
  /// chest and its shoulders do, are never contacts).
  std::vector<std::pair<int, int>> self_pairs;
};

/// Shapes of every link; self pairs are judged in configuration q_rest.
BodyShapes build_body_shapes(const core::Model& model, const Eigen::VectorXd& q_rest);

/// The capsule (or sphere, with half_length 0) that stands in for a shape in link–link tests:
/// boxes become the capsule along their longest axis that fits inside them.
struct CapsuleProxy {
  core::Vector3 a_W, b_W;  // segment ends, world
  double radius = 0;
};
CapsuleProxy capsule_proxy(const LinkShape& s, const core::Transform& X_WLink);

}  // namespace sim
