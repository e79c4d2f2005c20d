#include "sim/soft_contact.hpp"

#include <algorithm>
#include <cmath>

namespace sim {

namespace {

using core::Matrix3;
using core::Vector3;

// w(k s_catch) = 1 − e⁻⁵ ≈ 0.993: only a load within 0.7 % of μD F_z can creep
constexpr double kCatchFactor = 5.0;

double n_c(const PointState& s) { return static_cast<double>(std::max(1, s.points_in_pair)); }

}  // namespace

Trial trial_forces(const PointState& s, const ContactSettings& c) {
  Trial t;
  const double nc = n_c(s);
  const Vector3& n = s.normal_W;
  t.normal = std::max(0.0, (c.kp * s.depth - c.kd * n.dot(s.velocity_W)) / nc);  // eq. 6.14
  if (t.normal == 0) return t;
  const Matrix3 Pt = Matrix3::Identity() - n * n.transpose();
  // eq. 6.16, restoring form
  t.friction = (-c.kfp * (Pt * (s.position_W - s.anchor_W)) - c.kfd * (Pt * s.velocity_W)) / nc;
  return t;
}

FrictionState pair_friction(const Trial* trials, int count, const ContactSettings& c) {
  Vector3 total = Vector3::Zero();
  double normal = 0;
  for (int k = 0; k < count; ++k) {
    if (trials[k].normal <= 0) continue;
    total += trials[k].friction;
    normal += trials[k].normal;
  }
  return total.norm() <= c.mu_static * normal ? FrictionState::kStick : FrictionState::kSlide;
}

PointForce point_force(const PointState& s,
                       const ContactSettings& c,
                       FrictionState friction,
                       double h) {
  PointForce out;
  out.anchor_W = s.anchor_W;
  const double nc = n_c(s);
  const Vector3& n = s.normal_W;
  const double fz = (c.kp * s.depth - c.kd * n.dot(s.velocity_W)) / nc;  // eq. 6.14
  if (fz <= 0) {
    out.anchor_W = s.position_W;  // separating: the next touch anchors afresh
    return out;
  }
  out.normal_force = fz;
  const Matrix3 nnT = n * n.transpose();
  out.force_W = fz * n;
  // d decreases as the point moves out along n; u grows with the normal velocity
  const Vector3 dfz_dp = -(c.kp / nc) * n;
  const Vector3 dfz_dv = -(c.kd / nc) * n;
  out.dF_dp = n * dfz_dp.transpose();
  out.dF_dv = n * dfz_dv.transpose();
  if (friction == FrictionState::kOff) return out;

  const Matrix3 Pt = Matrix3::Identity() - nnT;  // projection onto the contact plane
  const Vector3 slip = Pt * s.velocity_W;
  if (friction == FrictionState::kStick) {
    out.force_W += (-c.kfp * (Pt * (s.position_W - s.anchor_W)) - c.kfd * slip) / nc;
    out.dF_dp -= (c.kfp / nc) * Pt;
    out.dF_dv -= (c.kfd / nc) * Pt;
    return out;
  }
  // dynamic friction, eqs. 6.17–6.20; the anchor follows the point
  out.anchor_W = s.position_W;
  const double pair_fz = s.pair_normal_force > 0 ? s.pair_normal_force : fz * nc;
  const double catch_speed = c.kfd > 0 ? c.mu_static * pair_fz / c.kfd : 0.0;
  const double k = std::max(c.smoothing / h, catch_speed > 0 ? kCatchFactor / catch_speed : 0.0);
  const double speed = slip.norm();
  // g(s) = w(|s|) s / |s| and its Jacobian G (eq. 6.37), with the small-|s| limits (6.41)
  Vector3 g;
  Matrix3 G;
  if (k * speed < 1e-8) {
    g = k * slip;
    G = k * Pt;
  } else {
    const double w = 1.0 - std::exp(-k * speed);
    const Vector3 dir = slip / speed;
    g = w * dir;
    G = (w / speed) * Pt + (k * std::exp(-k * speed) - w / speed) * dir * dir.transpose();
  }
  out.force_W -= c.mu_dynamic * fz * g;
  // through f_z: ∂f_t/∂p = μD (kP / n_C) g nᵀ (eq. 6.33), ∂f_t/∂u = μD (kD / n_C) g (eq. 6.38)
  out.dF_dp -= c.mu_dynamic * g * dfz_dp.transpose();
  out.dF_dv -= c.mu_dynamic * g * dfz_dv.transpose() + c.mu_dynamic * fz * G * Pt;
  return out;
}

}  // namespace sim
