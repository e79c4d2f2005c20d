// Spatial algebra: rigid transforms, motion and force vectors, spatial inertia.
// Spatial vectors are in Featherstone order [angular; linear] (RBDA ch. 2).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace core {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Quaternion = Eigen::Quaterniond;

/// Cross-product matrix: skew(a) * b == a.cross(b).
inline Matrix3 skew(const Vector3& a) {
  Matrix3 S;
  S << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return S;
}

/// Spatial motion vector (twist) [angular; linear]: angular velocity and the linear velocity of the
/// point at the frame origin, both in the frame's axes.
struct Motion {
  Vector3 angular = Vector3::Zero();
  Vector3 linear = Vector3::Zero();

  static Motion Zero() { return {}; }
  Vector6 vector() const {
    Vector6 out;
    out << angular, linear;
    return out;
  }
  static Motion from_vector(const Vector6& v) { return {v.head<3>(), v.tail<3>()}; }
  Motion operator+(const Motion& m) const { return {angular + m.angular, linear + m.linear}; }
  Motion operator-(const Motion& m) const { return {angular - m.angular, linear - m.linear}; }
  Motion operator*(double s) const { return {angular * s, linear * s}; }
  Motion& operator+=(const Motion& m) {
    angular += m.angular;
    linear += m.linear;
    return *this;
  }
  /// Motion cross product this ×m: the rate of change of m carried by this motion (RBDA eq. 2.31).
  Motion cross(const Motion& m) const {
    return {angular.cross(m.angular), angular.cross(m.linear) + linear.cross(m.angular)};
  }
};

/// Spatial force vector (wrench) [angular; linear]: moment about the frame origin and force.
struct Force {
  Vector3 angular = Vector3::Zero();
  Vector3 linear = Vector3::Zero();

  static Force Zero() { return {}; }
  Vector6 vector() const {
    Vector6 out;
    out << angular, linear;
    return out;
  }
  static Force from_vector(const Vector6& f) { return {f.head<3>(), f.tail<3>()}; }
  Force operator+(const Force& f) const { return {angular + f.angular, linear + f.linear}; }
  Force operator-(const Force& f) const { return {angular - f.angular, linear - f.linear}; }
  Force operator*(double s) const { return {angular * s, linear * s}; }
  Force& operator+=(const Force& f) {
    angular += f.angular;
    linear += f.linear;
    return *this;
  }
  Force& operator-=(const Force& f) {
    angular -= f.angular;
    linear -= f.linear;
    return *this;
  }
  /// Power of this force on a motion.
  double dot(const Motion& m) const { return angular.dot(m.angular) + linear.dot(m.linear); }
};

/// Force cross product v ×* f (RBDA eq. 2.32).
inline Force cross(const Motion& v, const Force& f) {
  return {v.angular.cross(f.angular) + v.linear.cross(f.linear), v.angular.cross(f.linear)};
}

/// Rigid transform X_AB: the pose of frame B in frame A, so p_A = X_AB * p_B = R * p_B + p.
struct Transform {
  Matrix3 R = Matrix3::Identity();
  Vector3 p = Vector3::Zero();

  static Transform Identity() { return {}; }
  static Transform from_translation(const Vector3& p) { return {Matrix3::Identity(), p}; }
  static Transform from_rotation(const Matrix3& R) { return {R, Vector3::Zero()}; }

  /// X_AC = X_AB * X_BC
  Transform operator*(const Transform& X_BC) const { return {R * X_BC.R, R * X_BC.p + p}; }
  Vector3 operator*(const Vector3& p_B) const { return R * p_B + p; }
  Transform inverse() const {
    const Matrix3 Rt = R.transpose();
    return {Rt, -(Rt * p)};
  }
  /// X_BA * p_A without forming the inverse.
  Vector3 inverse_apply(const Vector3& p_A) const { return R.transpose() * (p_A - p); }

  /// Motion given in B, re-expressed in A.
  Motion act(const Motion& m_B) const {
    const Vector3 w = R * m_B.angular;
    return {w, R * m_B.linear + p.cross(w)};
  }
  /// Motion given in A, re-expressed in B.
  Motion act_inverse(const Motion& m_A) const {
    return {R.transpose() * m_A.angular, R.transpose() * (m_A.linear - p.cross(m_A.angular))};
  }
  /// Force given in B, re-expressed in A.
  Force act(const Force& f_B) const {
    const Vector3 f = R * f_B.linear;
    return {R * f_B.angular + p.cross(f), f};
  }
  /// Force given in A, re-expressed in B.
  Force act_inverse(const Force& f_A) const {
    return {R.transpose() * (f_A.angular - p.cross(f_A.linear)), R.transpose() * f_A.linear};
  }
  /// 6x6 motion transform matrix (maps [ω; v] in B to A).
  Matrix6 motion_matrix() const;

  bool operator==(const Transform& o) const { return R == o.R && p == o.p; }
  bool is_approx(const Transform& o, double tol) const {
    return R.isApprox(o.R, tol) && (p - o.p).norm() <= tol * (1.0 + p.norm());
  }
};

/// Spatial inertia of a rigid body about the frame origin, stored in its additive form
/// (RBDA §2.13): mass m, first moment h = m c and rotational inertia I_O about the origin.
/// Composite inertias are plain sums in this form.
struct SpatialInertia {
  double mass = 0.0;
  Vector3 h = Vector3::Zero();    // first mass moment m * c
  Matrix3 I_O = Matrix3::Zero();  // rotational inertia about the frame origin

  /// From mass, centre of mass c and rotational inertia about the centre of mass (frame axes).
  static SpatialInertia from_com(double mass, const Vector3& com, const Matrix3& I_com);
  static SpatialInertia Zero() { return {}; }

  Vector3 com() const { return mass > 0 ? Vector3(h / mass) : Vector3::Zero(); }
  /// Rotational inertia about the centre of mass.
  Matrix3 inertia_about_com() const;

  /// Momentum h = I v.
  Force operator*(const Motion& v) const {
    return {I_O * v.angular + h.cross(v.linear), mass * v.linear - h.cross(v.angular)};
  }
  SpatialInertia operator+(const SpatialInertia& o) const {
    return {mass + o.mass, h + o.h, I_O + o.I_O};
  }
  SpatialInertia& operator+=(const SpatialInertia& o) {
    mass += o.mass;
    h += o.h;
    I_O += o.I_O;
    return *this;
  }
  /// This inertia (given in frame B) expressed in frame A, X = X_AB.
  SpatialInertia transformed(const Transform& X_AB) const;
  /// The 6 x 6 matrix [I_O  h×; −h×  m 1] (RBDA eq. 2.63 in the additive form).
  Matrix6 matrix() const {
    Matrix6 M;
    write_matrix(M);
    return M;
  }
  /// The same matrix written into M in place, entry by entry (no 6 x 6 temporary to move).
  void write_matrix(Matrix6& M) const {
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) {
        M(r, c) = I_O(r, c);
        M(r + 3, c + 3) = r == c ? mass : 0.0;
      }
    }
    // h× = [0 −h_z h_y; h_z 0 −h_x; −h_y h_x 0] in the top right, its negative (= transpose) below
    M(0, 3) = 0.0, M(0, 4) = -h.z(), M(0, 5) = h.y();
    M(1, 3) = h.z(), M(1, 4) = 0.0, M(1, 5) = -h.x();
    M(2, 3) = -h.y(), M(2, 4) = h.x(), M(2, 5) = 0.0;
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) M(r + 3, c) = -M(r, c + 3);
    }
  }

  bool operator==(const SpatialInertia& o) const {
    return mass == o.mass && h == o.h && I_O == o.I_O;
  }
};

/// Rotation matrix of the rotation vector w (Rodrigues' formula).
Matrix3 exp3(const Vector3& w);
/// Rotation vector of R, angle in [0, π]; accurate near 0 and near π.
Vector3 log3(const Matrix3& R);
/// Unit quaternion of the rotation vector w.
Quaternion quaternion_exp(const Vector3& w);
/// Rotation vector of a unit quaternion, angle in [0, π] (shortest path; q and -q agree).
Vector3 quaternion_log(const Quaternion& q);
/// Transform reached by following the body twist V for unit time: X(1) with X(0) = identity.
Transform exp6(const Motion& V);
/// Inverse of exp6.
Motion log6(const Transform& X);

}  // namespace core
