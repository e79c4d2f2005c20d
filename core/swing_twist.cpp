#include "core/swing_twist.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

namespace core {

namespace {
constexpr double kPi = std::numbers::pi;

// wrap to (−π, π]
double wrap_angle(double x) {
  x = std::remainder(x, 2 * kPi);
  if (x <= -kPi) x += 2 * kPi;
  return x;
}

// distance from point p to triangle abc in the plane, and barycentric coordinates
double point_triangle_distance(const Eigen::Vector2d& p,
                               const Eigen::Vector2d& a,
                               const Eigen::Vector2d& b,
                               const Eigen::Vector2d& c) {
  auto seg = [&](const Eigen::Vector2d& s0, const Eigen::Vector2d& s1) {
    const Eigen::Vector2d d = s1 - s0;
    const double t = std::clamp((p - s0).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
    return (s0 + t * d - p).norm();
  };
  return std::min({seg(a, b), seg(b, c), seg(c, a)});
}

bool barycentric(const Eigen::Vector2d& p,
                 const Eigen::Vector2d& a,
                 const Eigen::Vector2d& b,
                 const Eigen::Vector2d& c,
                 Eigen::Vector3d& lambda) {
  const Eigen::Vector2d e1 = b - a, e2 = c - a, d = p - a;
  const double det = e1.x() * e2.y() - e1.y() * e2.x();
  const double l1 = (d.x() * e2.y() - d.y() * e2.x()) / det;
  const double l2 = (e1.x() * d.y() - e1.y() * d.x()) / det;
  lambda = {1.0 - l1 - l2, l1, l2};
  constexpr double kEdgeTolerance = -1e-12;
  return lambda.minCoeff() >= kEdgeTolerance;
}

// distance of angle x (in (−π, π]) to the interval [lo, hi], modulo 2π
double twist_excess(double x, double lo, double hi) {
  double best = kInfinity;
  for (int k = -2; k <= 2; ++k) {
    const double y = x + 2 * kPi * k;
    const double d = y < lo ? lo - y : (y > hi ? y - hi : 0.0);
    best = std::min(best, d);
  }
  return best;
}
}  // namespace

SwingTwist swing_twist(const Quaternion& q) {
  SwingTwist out;
  const double c = std::sqrt(q.w() * q.w() + q.x() * q.x());  // cos(φ/2)
  if (c < 1e-9) {
    // swing of π: the twist is undefined; report zero twist and the swing axis in the y–z plane
    out.singular = true;
    out.a_y = q.y();
    out.a_z = q.z();
    const double n = std::hypot(out.a_y, out.a_z);
    if (n > 0) {
      out.a_y /= n;
      out.a_z /= n;
    }
    return out;
  }
  const double ct = q.w() / c, st = q.x() / c;  // cos(γ/2), sin(γ/2)
  out.twist = wrap_angle(2.0 * std::atan2(q.x(), q.w()));
  out.a_y = ct * q.y() - st * q.z();
  out.a_z = st * q.y() + ct * q.z();
  return out;
}

Quaternion from_swing_twist(double a_y, double a_z, double twist) {
  const double c = std::sqrt(std::max(0.0, 1.0 - a_y * a_y - a_z * a_z));
  const Quaternion swing(c, 0.0, a_y, a_z);
  const Quaternion tw(std::cos(0.5 * twist), std::sin(0.5 * twist), 0.0, 0.0);
  return swing * tw;
}

SwingTwist joint_swing_twist(const Model& model, int i, const Quaternion& q_joint) {
  // change of basis into the range frame: q_range = F⁻¹ q F
  const Quaternion& F = model.spherical_range[i].frame;
  return swing_twist(F.conjugate() * q_joint * F);
}

Eigen::Vector2d swing_toward(double psi, double phi) {
  // axis = x × (0, cos ψ, sin ψ) = (0, −sin ψ, cos ψ); a = sin(φ/2) axis
  const double s = std::sin(0.5 * phi);
  return {-s * std::sin(psi), s * std::cos(psi)};
}

RangeStatus check_range(const SphericalRange& range, const SwingTwist& st) {
  RangeStatus out;
  if (range.empty()) return out;
  const Eigen::Vector2d a(st.a_y, st.a_z);
  double best_twist_excess = kInfinity;
  for (size_t t = 0; t < range.triangles.size(); ++t) {
    const auto& tri = range.triangles[t];
    const Eigen::Vector2d& A = range.swing[tri[0]];
    const Eigen::Vector2d& B = range.swing[tri[1]];
    const Eigen::Vector2d& C = range.swing[tri[2]];
    Eigen::Vector3d l;
    if (!barycentric(a, A, B, C, l)) continue;
    const double lo = l[0] * range.twist_lower[tri[0]] + l[1] * range.twist_lower[tri[1]] +
                      l[2] * range.twist_lower[tri[2]];
    const double hi = l[0] * range.twist_upper[tri[0]] + l[1] * range.twist_upper[tri[1]] +
                      l[2] * range.twist_upper[tri[2]];
    const double excess = st.singular ? 0.0 : twist_excess(st.twist, lo, hi);
    if (excess < best_twist_excess) {
      best_twist_excess = excess;
      out.triangle = static_cast<int>(t);
      out.twist_lower = lo;
      out.twist_upper = hi;
    }
    if (excess == 0) break;
  }
  if (out.triangle < 0) {
    // outside every triangle (only then is the distance to the patch needed): |a| = sin(φ/2),
    // so a distance d in the swing plane is at least 2d in swing angle
    double swing_distance = kInfinity;
    for (const auto& tri : range.triangles) {
      swing_distance = std::min(swing_distance,
                                point_triangle_distance(a, range.swing[tri[0]], range.swing[tri[1]],
                                                        range.swing[tri[2]]));
    }
    out.inside = false;
    out.violation = 2.0 * swing_distance;
    return out;
  }
  out.inside = best_twist_excess == 0;
  out.violation = best_twist_excess;
  return out;
}

RangeInnerBounds inner_bounds(const SphericalRange& range) {
  RangeInnerBounds b;
  if (range.empty()) return b;
  // the nominal direction (a = 0) must be inside some triangle
  bool origin_inside = false;
  for (const auto& t : range.triangles) {
    Eigen::Vector3d l;
    origin_inside = origin_inside || barycentric(Eigen::Vector2d::Zero(), range.swing[t[0]],
                                                 range.swing[t[1]], range.swing[t[2]], l);
  }
  b.twist_lower = -kInfinity;
  b.twist_upper = kInfinity;
  for (size_t v = 0; v < range.swing.size(); ++v) {
    b.twist_lower = std::max(b.twist_lower, range.twist_lower[v]);
    b.twist_upper = std::min(b.twist_upper, range.twist_upper[v]);
  }
  if (!origin_inside) return b;
  // boundary edges belong to one triangle only; the disk may reach the nearest of them
  std::map<std::pair<int, int>, int> uses;  // undirected edge → number of triangles using it
  for (const auto& t : range.triangles) {
    for (int e = 0; e < 3; ++e) {
      const int a = t[e], c = t[(e + 1) % 3];
      ++uses[{std::min(a, c), std::max(a, c)}];
    }
  }
  double r = kInfinity;
  for (const auto& [edge, count] : uses) {
    if (count != 1) continue;
    const Eigen::Vector2d& p0 = range.swing[edge.first];
    const Eigen::Vector2d& p1 = range.swing[edge.second];
    const Eigen::Vector2d d = p1 - p0;
    const double s = std::clamp(-p0.dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
    r = std::min(r, (p0 + s * d).norm());
  }
  // shrink a hair so rounding at the rim never accepts a point the full test would refuse
  b.swing_radius = std::isfinite(r) ? r * (1.0 - 1e-9) : -1;
  // a rotation by θ: its swing angle φ ≤ θ (the angle between x and R x) and its twist
  // |γ| = 2 atan2(|v_x|, |w|) ≤ 2 atan2(|v|, |w|) = θ; so sin(θ/2) ≤ the swing radius and θ within
  // the twist interval every vertex allows (a range frame is a change of basis: θ is the same)
  const double twist_reach = std::min(b.twist_upper, -b.twist_lower);
  if (b.swing_radius >= 0 && twist_reach >= 0) {
    const double twist_sin_half = twist_reach >= kPi ? 1.0 : std::sin(0.5 * twist_reach);
    b.rotation_sin_half = std::min(b.swing_radius, twist_sin_half * (1.0 - 1e-9));
  }
  return b;
}

bool joint_rotation_surely_inside(const Model& model, int i, const Quaternion& q_joint) {
  const double s = model.range_inner[i].rotation_sin_half;
  // |v|² ≤ s² |q|²: sin²(θ/2) ≤ s², without normalizing q
  return s >= 0 && q_joint.vec().squaredNorm() <= s * s * q_joint.squaredNorm();
}

RangeStatus joint_range_status(const Model& model, int i, const Quaternion& q_joint) {
  if (joint_rotation_surely_inside(model, i, q_joint)) return RangeStatus{};
  return check_joint_range(model, i, joint_swing_twist(model, i, q_joint));
}

RangeStatus check_joint_range(const Model& model, int i, const SwingTwist& st) {
  const RangeInnerBounds& b = model.range_inner[i];
  if (!st.singular && st.a_y * st.a_y + st.a_z * st.a_z <= b.swing_radius * b.swing_radius &&
      b.swing_radius >= 0 && twist_excess(st.twist, b.twist_lower, b.twist_upper) == 0) {
    return RangeStatus{};
  }
  return check_range(model.spherical_range[i], st);
}

SphericalRange directional_range(const std::vector<double>& psi,
                                 const std::vector<double>& swing_max,
                                 const std::vector<double>& twist_lower,
                                 const std::vector<double>& twist_upper,
                                 double centre_twist_lower,
                                 double centre_twist_upper) {
  SphericalRange r;
  const int n = static_cast<int>(psi.size());
  r.swing.push_back(Eigen::Vector2d::Zero());
  r.twist_lower.push_back(centre_twist_lower);
  r.twist_upper.push_back(centre_twist_upper);
  for (int k = 0; k < n; ++k) {
    r.swing.push_back(swing_toward(psi[k], swing_max[k]));
    r.twist_lower.push_back(twist_lower[k]);
    r.twist_upper.push_back(twist_upper[k]);
  }
  for (int k = 0; k < n; ++k) r.triangles.push_back({0, 1 + k, 1 + (k + 1) % n});
  return r;
}

SphericalRange cone_range(double swing_max, double twist_lower, double twist_upper, int segments) {
  std::vector<double> psi, swing, lo, hi;
  for (int k = 0; k < segments; ++k) {
    psi.push_back(2 * kPi * k / segments);
    swing.push_back(swing_max);
    lo.push_back(twist_lower);
    hi.push_back(twist_upper);
  }
  return directional_range(psi, swing, lo, hi, twist_lower, twist_upper);
}

}  // namespace core
