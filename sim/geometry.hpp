// Closest-point queries between the convex primitives of the contact search.
#pragma once

#include "core/spatial.hpp"

namespace sim {

/// Closest points of segments [p0, p1] and [q0, q1] (either may be a point); returns the squared
/// distance. Ericson, Real-Time Collision Detection §5.1.9.
double segment_closest_points(const core::Vector3& p0,
                              const core::Vector3& p1,
                              const core::Vector3& q0,
                              const core::Vector3& q1,
                              core::Vector3& on_p,
                              core::Vector3& on_q);

/// Where a point meets a solid box (pose X_WBox, half extents h).
struct BoxQuery {
  core::Vector3 closest_W;  // closest point of the box (the point itself when inside)
  bool inside = false;
  core::Vector3 face_normal_W;  // inside: outward normal of the nearest face
  double face_depth = 0;        // inside: distance to that face
};
BoxQuery query_box(const core::Transform& X_WBox, const core::Vector3& h, const core::Vector3& p_W);

}  // namespace sim
