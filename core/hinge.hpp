// Fast paths for hinges, the common joint of a character: a revolute joint about a principal axis
// of its frame with an unrotated placement. Internal to the kinematics and dynamics kernels.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <type_traits>

#include "core/model.hpp"
#include "core/spatial.hpp"

namespace core {

/// sin(x) and cos(x) together, within 2 ulp of std::sin and std::cos (checked on 1.2e7 samples
/// up to |x| = 1e5) and cheaper than the library call, which was a third of forward kinematics;
/// this one inlines into the joint loop. x is reduced by the
/// nearest multiple n of π/2 with π/2 split in three parts (Cody–Waite: n * kPi2a and n * kPi2b
/// are exact for |n| < 2^20), then sin and cos of r in [−π/4, π/4] are their Taylor polynomials
/// (truncation below 1e-16 relative). The library handles |x| ≥ 1e5 and non-finite x.
inline void sin_cos(double x, double& s, double& c) {
  if (!(std::abs(x) < 1e5)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  constexpr double k2OverPi = 0.6366197723675814;
  constexpr double kPi2a = 1.5707963267341256;      // π/2 to 33 bits
  constexpr double kPi2b = 6.077100506303966e-11;   // the next 33 bits
  constexpr double kPi2c = 2.0222662487959506e-21;  // the rest
  constexpr double kRound = 6755399441055744.0;     // 1.5 * 2^52: adding it rounds to integer
  const double n = (x * k2OverPi + kRound) - kRound;
  const double r = ((x - n * kPi2a) - n * kPi2b) - n * kPi2c;
  const double r2 = r * r;
  // sin r = r − r³/3! + … − r¹⁵/15!,  cos r = 1 − r²/2! + … + r¹⁶/16!
  const double sr =
      r + r * r2 *
              (-1.0 / 6 +
               r2 * (1.0 / 120 +
                     r2 * (-1.0 / 5040 +
                           r2 * (1.0 / 362880 +
                                 r2 * (-1.0 / 39916800 +
                                       r2 * (1.0 / 6227020800 + r2 * (-1.0 / 1307674368000)))))));
  const double cr =
      1.0 +
      r2 * (-0.5 +
            r2 * (1.0 / 24 +
                  r2 * (-1.0 / 720 +
                        r2 * (1.0 / 40320 +
                              r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600 +
                                                           r2 * (-1.0 / 87178291200 +
                                                                 r2 * (1.0 / 20922789888000))))))));
  switch (static_cast<int>(n) & 3) {  // x = r + n π/2
    case 0:
      s = sr;
      c = cr;
      break;
    case 1:
      s = cr;
      c = -sr;
      break;
    case 2:
      s = -sr;
      c = -cr;
      break;
    default:
      s = -cr;
      c = sr;
      break;
  }
}

/// Rotation about the principal axis K (0, 1, 2: x, y, z) by an angle with cosine c and sine s,
/// applied without forming the 3 × 3 matrix: it mixes only the two other coordinates. The axis is
/// a template parameter so the coordinates are known at compile time (use with_axis to dispatch).
template <int K>
struct AxisRotation {
  static constexpr int k = K, k1 = (K + 1) % 3, k2 = (K + 2) % 3;
  double c, s;

  /// The rotation R of a matrix known to be a rotation about axis K.
  static AxisRotation of(const Matrix3& R) { return {R(k1, k1), R(k2, k1)}; }
  /// R x
  Vector3 apply(const Vector3& x) const {
    Vector3 out;
    out[k] = x[k];
    out[k1] = c * x[k1] - s * x[k2];
    out[k2] = s * x[k1] + c * x[k2];
    return out;
  }
  /// Rᵀ x
  Vector3 apply_transpose(const Vector3& x) const {
    Vector3 out;
    out[k] = x[k];
    out[k1] = c * x[k1] + s * x[k2];
    out[k2] = c * x[k2] - s * x[k1];
    return out;
  }
  /// The 3 × 3 matrix.
  Matrix3 matrix() const {
    Matrix3 R;
    R(k, k) = 1;
    R(k1, k) = R(k2, k) = R(k, k1) = R(k, k2) = 0;
    R(k1, k1) = c;
    R(k2, k1) = s;
    R(k1, k2) = -s;
    R(k2, k2) = c;
    return R;
  }
};

/// Calls f(std::integral_constant<int, K>{}) with K = k for a principal axis k in {0, 1, 2}: one
/// branch per joint, then code specialized for the axis.
template <typename F>
inline decltype(auto) with_axis(int k, F&& f) {
  switch (k) {
    case 0:
      return f(std::integral_constant<int, 0>{});
    case 1:
      return f(std::integral_constant<int, 1>{});
    default:
      return f(std::integral_constant<int, 2>{});
  }
}

/// A hinge: a revolute joint about a principal axis of its frame whose placement is a pure
/// translation, so X_P = (R_k(q), p). Most joints of a character are hinges, and every kernel has
/// a fast path for them: S = [e_k; 0] selects entries instead of multiplying.
inline bool is_hinge(const Model& model, int i) {
  return model.joint_type[i] == JointType::kRevolute && model.axis_index[i] >= 0 &&
         model.placement_is_translation[i];
}

/// The joint rotation of hinge i (axis K) at configuration q.
template <int K>
inline AxisRotation<K> hinge_rotation(const Model& model, int i, const Eigen::VectorXd& q) {
  AxisRotation<K> r;
  sin_cos(q[model.idx_q[i]], r.s, r.c);
  return r;
}

/// X_P = (R, p) of a hinge with R a rotation about principal axis K: motion and force transforms
/// at the cost of axis rotations (4 products per vector instead of 9) and one cross product.
template <int K>
struct HingeTransform {
  AxisRotation<K> r;
  Vector3 p;

  /// The hinge transform of X_P, which must be a hinge's (is_hinge) with axis K.
  static HingeTransform of(const Transform& X_P) { return {AxisRotation<K>::of(X_P.R), X_P.p}; }
  Transform transform() const { return {r.matrix(), p}; }
  /// Motion in the parent, re-expressed in the child: (Rᵀ ω, Rᵀ (v − p × ω)).
  Motion act_inverse(const Motion& m) const {
    return {r.apply_transpose(m.angular), r.apply_transpose(m.linear - p.cross(m.angular))};
  }
  /// Force in the child, re-expressed in the parent: (R n + p × R f, R f).
  Force act(const Force& f) const {
    const Vector3 lin = r.apply(f.linear);
    return {r.apply(f.angular) + p.cross(lin), lin};
  }
};

/// v × (S q̇) for S = [e_K; 0] (RBDA eq. 2.31 with a unit axis): (ω × e_K, v × e_K) q̇.
template <int K>
inline Motion cross_axis(const Motion& v, double qd) {
  constexpr int k1 = (K + 1) % 3, k2 = (K + 2) % 3;
  Motion out;
  // a × e_K has a_k2 in entry k1 and −a_k1 in entry k2
  out.angular[K] = 0;
  out.angular[k1] = v.angular[k2] * qd;
  out.angular[k2] = -v.angular[k1] * qd;
  out.linear[K] = 0;
  out.linear[k1] = v.linear[k2] * qd;
  out.linear[k2] = -v.linear[k1] * qd;
  return out;
}

/// M x for a 3 x 3 matrix, as a sum of scaled columns (inlines where the generic product does not).
inline Vector3 mul(const Matrix3& M, const Vector3& x) {
  return M.col(0) * x[0] + M.col(1) * x[1] + M.col(2) * x[2];
}

/// Momentum I v of a spatial inertia (as SpatialInertia::operator*, inlined).
inline Force inertia_times(const SpatialInertia& I, const Motion& v) {
  return {mul(I.I_O, v.angular) + I.h.cross(v.linear), I.mass * v.linear - I.h.cross(v.angular)};
}

/// True when a body has no mass and no rotational inertia (the massless links between the axes
/// of a multi-axis joint): its inertia products vanish.
inline bool is_massless(const SpatialInertia& I) {
  return I.mass == 0 && I.I_O(0, 0) == 0 && I.I_O(1, 1) == 0 && I.I_O(2, 2) == 0 &&
         I.I_O(0, 1) == 0 && I.I_O(0, 2) == 0 && I.I_O(1, 2) == 0;
}

}  // namespace core
