#include "sim/support_polygon.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace sim {

namespace {

using core::Vector3;
using Point = Eigen::Vector2d;

constexpr double kSame = 1e-9;  // m: points closer than this are one

// Axes (u, w) of the plane with u × w = n, so counter-clockwise in (u, w) is counter-clockwise
// seen from above the ground.
struct PlaneAxes {
  Vector3 origin, n, u, w;
  explicit PlaneAxes(const GroundPlane& g) : origin(g.point), n(g.normal.normalized()) {
    const Vector3 a = std::abs(n.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitZ();
    u = (a - a.dot(n) * n).normalized();
    w = n.cross(u);
  }
  Point flat(const Vector3& p) const { return {(p - origin).dot(u), (p - origin).dot(w)}; }
  Vector3 lift(const Point& p) const { return origin + p.x() * u + p.y() * w; }
};

double cross_z(const Point& o, const Point& a, const Point& b) {
  const Point oa = a - o, ob = b - o;
  return oa.x() * ob.y() - oa.y() * ob.x();
}

// Andrew's monotone chain: the hull counter-clockwise, without collinear points.
std::vector<Point> hull(std::vector<Point> p) {
  std::sort(p.begin(), p.end(), [](const Point& a, const Point& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  p.erase(std::unique(p.begin(), p.end(),
                      [](const Point& a, const Point& b) { return (a - b).norm() < kSame; }),
          p.end());
  if (p.size() < 3) return p;
  std::vector<Point> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {  // lower chain
    while (k >= 2 && cross_z(h[k - 2], h[k - 1], p[i]) <= kSame * kSame) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {  // upper chain
    while (k >= lower && cross_z(h[k - 2], h[k - 1], p[i]) <= kSame * kSame) --k;
    h[k++] = p[i];
  }
  h.resize(k - 1);  // the last point is the first
  return h;
}

double distance_to_segment(const Point& p, const Point& a, const Point& b) {
  const Point ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

}  // namespace

std::vector<Vector3> support_polygon(const std::vector<Vector3>& points,
                                     const GroundPlane& ground) {
  const PlaneAxes axes(ground);
  std::vector<Point> flat;
  flat.reserve(points.size());
  for (const Vector3& p : points) flat.push_back(axes.flat(p));
  std::vector<Vector3> out;
  for (const Point& p : hull(std::move(flat))) out.push_back(axes.lift(p));
  return out;
}

Vector3 polygon_centroid(const std::vector<Vector3>& polygon, const GroundPlane& ground) {
  const PlaneAxes axes(ground);
  Point mean = Point::Zero();
  for (const Vector3& v : polygon) mean += axes.flat(v);
  mean /= static_cast<double>(std::max<std::size_t>(polygon.size(), 1));
  // the shoelace formula over triangles fanned from the mean
  double area = 0;
  Point moment = Point::Zero();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Point a = axes.flat(polygon[i]), b = axes.flat(polygon[(i + 1) % polygon.size()]);
    const double t = 0.5 * cross_z(mean, a, b);
    area += t;
    moment += t * (mean + a + b) / 3.0;
  }
  return axes.lift(area > 1e-12 ? Point(moment / area) : mean);
}

Vector3 clamp_toward(const std::vector<Vector3>& polygon,
                     const Vector3& point,
                     const Vector3& centre,
                     const GroundPlane& ground,
                     double margin) {
  const PlaneAxes axes(ground);
  const Point c = axes.flat(centre), d = axes.flat(point) - c;
  if (polygon.size() < 3) return axes.lift(c);
  // each edge a→b keeps the points whose signed distance to its left is at least `margin`; along
  // c + t d that distance is s(c) + t s'(d), so t may grow to (s(c) − margin) / −s'(d)
  double t = 1.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Point a = axes.flat(polygon[i]), b = axes.flat(polygon[(i + 1) % polygon.size()]);
    const double length = (b - a).norm();
    if (!(length > 0)) continue;
    const double at_centre = cross_z(a, b, c) / length - margin;
    if (at_centre < 0) return axes.lift(c);  // the centre itself is not that far inside
    const double rate = ((b - a).x() * d.y() - (b - a).y() * d.x()) / length;
    if (rate < 0) t = std::min(t, at_centre / -rate);
  }
  return axes.lift(c + t * d);
}

bool inside_polygon(const std::vector<Vector3>& polygon,
                    const Vector3& point,
                    const GroundPlane& ground,
                    double tolerance) {
  if (polygon.empty()) return false;
  const PlaneAxes axes(ground);
  const Point p = axes.flat(point);
  const std::size_t n = polygon.size();
  if (n < 3) {
    return distance_to_segment(p, axes.flat(polygon.front()), axes.flat(polygon.back())) <=
           tolerance;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Point a = axes.flat(polygon[i]), b = axes.flat(polygon[(i + 1) % n]);
    // signed distance of p to the left of edge a→b (inside is to the left)
    if (cross_z(a, b, p) / (b - a).norm() < -tolerance) return false;
  }
  return true;
}

}  // namespace sim
