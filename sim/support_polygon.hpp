// The support polygon of a standing figure: the convex hull of its contact points projected onto
// the ground plane (Andrew's monotone chain), and whether a point of the plane lies inside it.
#pragma once

#include <vector>

#include "core/spatial.hpp"
#include "sim/environment.hpp"

namespace sim {

/// The convex hull of `points` projected onto `ground`, counter-clockwise seen from the side the
/// normal points to; collinear and repeated points (within 1e-9 m) dropped. Fewer than three
/// vertices when the points are fewer or collinear (a point, a segment).
std::vector<core::Vector3> support_polygon(const std::vector<core::Vector3>& points,
                                           const GroundPlane& ground);

/// The centroid of the area of `polygon` (as support_polygon returns it), on the plane; the mean
/// of its points when it has no area (a point, a segment).
core::Vector3 polygon_centroid(const std::vector<core::Vector3>& polygon,
                               const GroundPlane& ground);

/// The point of the segment from `centre` to `point` (both projected onto `ground`) nearest
/// `point` that lies at least `margin` inside the convex `polygon` (as support_polygon returns
/// it): `point` itself when it does, `centre` when not even it does.
core::Vector3 clamp_toward(const std::vector<core::Vector3>& polygon,
                           const core::Vector3& point,
                           const core::Vector3& centre,
                           const GroundPlane& ground,
                           double margin);

/// `point` projected onto `ground` lies inside the convex `polygon` (as support_polygon returns
/// it) or within `tolerance` (m) of it. False for an empty polygon.
bool inside_polygon(const std::vector<core::Vector3>& polygon,
                    const core::Vector3& point,
                    const GroundPlane& ground,
                    double tolerance);

}  // namespace sim
