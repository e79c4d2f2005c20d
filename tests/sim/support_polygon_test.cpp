// The support polygon's centroid and the clamp of a desired centre of pressure into it
// (sim/support_polygon.hpp), on the default ground (+y up) and a tilted one.
#include <gtest/gtest.h>

#include <cmath>

#include "sim/support_polygon.hpp"

namespace {

using core::Vector3;

// a 0.2 m × 0.4 m rectangle on the ground, x in [0, 0.2], z in [0, 0.4]
std::vector<Vector3> rectangle() {
  return sim::support_polygon({{0, 0, 0}, {0.2, 0, 0}, {0.2, 0, 0.4}, {0, 0, 0.4}, {0.1, 0, 0.1}},
                              {});
}

TEST(SupportPolygon, CentroidOfAnAreaNotOfItsCorners) {
  // a triangle with an extra vertex crowding one corner: the vertex mean moves, the area's does not
  const std::vector<Vector3> p =
      sim::support_polygon({{0, 0, 0}, {0.3, 0, 0}, {0, 0, 0.3}, {0.01, 0, 0}}, {});
  EXPECT_LT((sim::polygon_centroid(p, {}) - Vector3(0.1, 0, 0.1)).norm(), 1e-12);
  EXPECT_LT((sim::polygon_centroid(rectangle(), {}) - Vector3(0.1, 0, 0.2)).norm(), 1e-12);
}

TEST(SupportPolygon, ClampStopsAMarginInsideAlongTheSegmentToTheCentre) {
  const std::vector<Vector3> r = rectangle();
  const Vector3 centre(0.1, 0, 0.2);
  // inside by more than the margin: kept
  EXPECT_EQ(sim::clamp_toward(r, Vector3(0.15, 0, 0.3), centre, {}, 0.02), Vector3(0.15, 0, 0.3));
  // beyond the x = 0.2 edge: stopped 0.02 inside it, on the way to the centre
  const Vector3 c = sim::clamp_toward(r, Vector3(0.5, 0, 0.2), centre, {}, 0.02);
  EXPECT_NEAR(c.x(), 0.18, 1e-12);
  EXPECT_NEAR(c.z(), 0.2, 1e-12);
  // beyond a corner: the nearer edge along the segment decides, and the point is inside
  const Vector3 d = sim::clamp_toward(r, Vector3(0.4, 0, 1.0), centre, {}, 0.01);
  EXPECT_TRUE(sim::inside_polygon(r, d, {}, -0.01 + 1e-12));
  EXPECT_FALSE(sim::inside_polygon(r, d, {}, -0.01 - 1e-9)) << "not deeper than it must be";
  // a margin wider than the polygon allows: the centre
  EXPECT_EQ(sim::clamp_toward(r, Vector3(0.5, 0, 0.2), centre, {}, 0.15), centre);
}

TEST(SupportPolygon, ClampOnATiltedGround) {
  sim::GroundPlane tilted;
  tilted.normal = Vector3(std::sin(0.3), std::cos(0.3), 0);
  const Vector3 u(std::cos(0.3), -std::sin(0.3), 0), w(0, 0, 1);  // axes of the plane
  std::vector<Vector3> corners;
  for (const auto& [a, b] : {std::pair{0.0, 0.0}, {0.2, 0.0}, {0.2, 0.4}, {0.0, 0.4}}) {
    corners.push_back(a * u + b * w);
  }
  const std::vector<Vector3> r = sim::support_polygon(corners, tilted);
  const Vector3 centre = 0.1 * u + 0.2 * w;
  const Vector3 c = sim::clamp_toward(r, 0.5 * u + 0.2 * w, centre, tilted, 0.02);
  EXPECT_LT((c - (0.18 * u + 0.2 * w)).norm(), 1e-12);
}

}  // namespace
