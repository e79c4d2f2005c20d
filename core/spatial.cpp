#include "core/spatial.hpp"

#include <cmath>

namespace core {

Matrix6 Transform::motion_matrix() const {
  Matrix6 X = Matrix6::Zero();
  X.topLeftCorner<3, 3>() = R;
  X.bottomRightCorner<3, 3>() = R;
  X.bottomLeftCorner<3, 3>() = skew(p) * R;
  return X;
}

SpatialInertia SpatialInertia::from_com(double mass, const Vector3& com, const Matrix3& I_com) {
  // parallel-axis theorem: I_O = I_c + m (|c|² E - c cᵀ)
  SpatialInertia I;
  I.mass = mass;
  I.h = mass * com;
  I.I_O = I_com + mass * (com.squaredNorm() * Matrix3::Identity() - com * com.transpose());
  return I;
}

Matrix3 SpatialInertia::inertia_about_com() const {
  if (mass <= 0) return I_O;
  const Vector3 c = h / mass;
  return I_O - mass * (c.squaredNorm() * Matrix3::Identity() - c * c.transpose());
}

SpatialInertia SpatialInertia::transformed(const Transform& X_AB) const {
  // rotate about B's origin, then shift the reference point from B's origin to A's origin:
  // I_A = R I Rᵀ + m(|p|² E - p pᵀ) + 2 (pᵀh') E - (p h'ᵀ + h' pᵀ), h_A = h' + m p, h' = R h.
  // I_A is symmetric: its six distinct entries are formed and mirrored (45 products for R I Rᵀ
  // instead of 54, and no 3×3 temporaries for the shift).
  const Matrix3& R = X_AB.R;
  const Vector3& p = X_AB.p;
  const Vector3 h_rot = R * h;
  const Matrix3 RI = R * I_O;
  SpatialInertia out;
  out.mass = mass;
  out.h = h_rot + mass * p;
  const double diagonal_shift = mass * p.squaredNorm() + 2.0 * p.dot(h_rot);
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r <= c; ++r) {
      const double v = RI(r, 0) * R(c, 0) + RI(r, 1) * R(c, 1) + RI(r, 2) * R(c, 2) -
                       mass * p[r] * p[c] - (p[r] * h_rot[c] + h_rot[r] * p[c]);
      out.I_O(r, c) = v;
      out.I_O(c, r) = v;
    }
    out.I_O(c, c) += diagonal_shift;
  }
  return out;
}

Matrix3 exp3(const Vector3& w) {
  const double theta2 = w.squaredNorm();
  const Matrix3 W = skew(w);
  double a, b;  // R = E + a W + b W²
  if (theta2 < 1e-8) {
    // Taylor series: sin(t)/t and (1 - cos t)/t² to fourth order
    a = 1.0 - theta2 / 6.0 + theta2 * theta2 / 120.0;
    b = 0.5 - theta2 / 24.0 + theta2 * theta2 / 720.0;
  } else {
    const double theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  return Matrix3::Identity() + a * W + b * W * W;
}

Vector3 log3(const Matrix3& R) {
  // angle from the quaternion is accurate over the whole range, unlike acos(trace)
  return quaternion_log(Quaternion(R));
}

Quaternion quaternion_exp(const Vector3& w) {
  const double theta2 = w.squaredNorm();
  double s, c;  // q = (cos(t/2), sin(t/2)/t * w)
  if (theta2 < 1e-8) {
    s = 0.5 - theta2 / 48.0;
    c = 1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0;
  } else {
    const double theta = std::sqrt(theta2);
    s = std::sin(0.5 * theta) / theta;
    c = std::cos(0.5 * theta);
  }
  return Quaternion(c, s * w.x(), s * w.y(), s * w.z());
}

Vector3 quaternion_log(const Quaternion& q_in) {
  // shortest path: pick the hemisphere with w >= 0
  const Quaternion q = q_in.w() < 0 ? Quaternion(-q_in.w(), -q_in.x(), -q_in.y(), -q_in.z()) : q_in;
  const Vector3 v = q.vec();
  const double s = v.norm();
  // θ = 2 atan2(|v|, w) is well conditioned at both ends of [0, π]
  const double theta = 2.0 * std::atan2(s, q.w());
  if (s < 1e-12) return (2.0 / q.w()) * v;  // small angle: θ/s → 2/w
  return (theta / s) * v;
}

namespace {
// coefficients of V(ω) = E + b W + c W², with b = (1 - cos t)/t², c = (t - sin t)/t³
void left_jacobian_coefficients(double theta2, double& b, double& c) {
  if (theta2 < 1e-8) {
    b = 0.5 - theta2 / 24.0;
    c = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    const double theta = std::sqrt(theta2);
    b = (1.0 - std::cos(theta)) / theta2;
    c = (theta - std::sin(theta)) / (theta2 * theta);
  }
}
}  // namespace

Transform exp6(const Motion& V) {
  const Matrix3 W = skew(V.angular);
  double b, c;
  left_jacobian_coefficients(V.angular.squaredNorm(), b, c);
  const Matrix3 J = Matrix3::Identity() + b * W + c * W * W;
  return {exp3(V.angular), J * V.linear};
}

Motion log6(const Transform& X) {
  const Vector3 w = log3(X.R);
  const double theta2 = w.squaredNorm();
  const Matrix3 W = skew(w);
  // V(ω)^-1 = E - W/2 + d W², d = (1 - t sin t / (2 (1 - cos t))) / t²
  double d;
  if (theta2 < 1e-8) {
    d = 1.0 / 12.0 + theta2 / 720.0;
  } else {
    const double theta = std::sqrt(theta2);
    d = (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / theta2;
  }
  const Matrix3 Jinv = Matrix3::Identity() - 0.5 * W + d * W * W;
  return {w, Jinv * X.p};
}

}  // namespace core
