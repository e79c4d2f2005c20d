#include "sim/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace sim {

using core::Vector3;

double segment_closest_points(const Vector3& p0,
                              const Vector3& p1,
                              const Vector3& q0,
                              const Vector3& q1,
                              Vector3& on_p,
                              Vector3& on_q) {
  const Vector3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  constexpr double kEps = 1e-18;
  double s = 0, t = 0;
  if (a <= kEps && e <= kEps) {
    // two points
  } else if (a <= kEps) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kEps) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      // parallel segments (denom 0): any s works, take the start
      s = denom > kEps * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  on_p = p0 + s * d1;
  on_q = q0 + t * d2;
  return (on_p - on_q).squaredNorm();
}

BoxQuery query_box(const core::Transform& X_WBox, const Vector3& h, const Vector3& p_W) {
  const Vector3 p = X_WBox.inverse_apply(p_W);
  const Vector3 clamped = p.cwiseMax(-h).cwiseMin(h);
  BoxQuery out;
  out.inside = clamped == p;
  if (!out.inside) {
    out.closest_W = X_WBox * clamped;
    return out;
  }
  out.closest_W = p_W;
  // the face with the smallest distance to the point
  int axis = 0;
  double best = std::numeric_limits<double>::infinity();
  double sign = 1;
  for (int k = 0; k < 3; ++k) {
    for (const double s : {1.0, -1.0}) {
      const double d = h[k] - s * p[k];
      if (d < best) {
        best = d;
        axis = k;
        sign = s;
      }
    }
  }
  out.face_depth = best;
  out.face_normal_W = X_WBox.R * (sign * Vector3::Unit(axis));
  return out;
}

}  // namespace sim
