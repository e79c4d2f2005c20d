// Tests for sim/soft_contact.hpp: the point force law of Yamane §6.3 and its derivatives.
#include "sim/soft_contact.hpp"

#include <gtest/gtest.h>

namespace {

using core::Matrix3;
using core::Vector3;

sim::PointState touching(const Vector3& velocity, const Vector3& stretch) {
  sim::PointState s;
  s.normal_W = Vector3(0.1, 1.0, -0.2).normalized();
  s.position_W = Vector3(0.3, -0.002, 0.1);
  s.anchor_W = s.position_W - stretch;
  s.velocity_W = velocity;
  s.depth = 0.002;
  s.points_in_pair = 4;
  return s;
}

// ∂f/∂p and ∂f/∂ṗ by central differences: moving the point by δ changes its depth by −n·δ
void numeric_derivatives(const sim::PointState& s,
                         const sim::ContactSettings& c,
                         sim::FrictionState mode,
                         double h,
                         Matrix3& dp,
                         Matrix3& dv) {
  const double e = 1e-7;
  for (int k = 0; k < 3; ++k) {
    sim::PointState a = s, b = s;
    const Vector3 d = e * Vector3::Unit(k);
    a.position_W += d;
    a.depth -= s.normal_W.dot(d);
    b.position_W -= d;
    b.depth += s.normal_W.dot(d);
    dp.col(k) =
        (sim::point_force(a, c, mode, h).force_W - sim::point_force(b, c, mode, h).force_W) /
        (2 * e);
    a = s;
    b = s;
    a.velocity_W += d;
    b.velocity_W -= d;
    dv.col(k) =
        (sim::point_force(a, c, mode, h).force_W - sim::point_force(b, c, mode, h).force_W) /
        (2 * e);
  }
}

TEST(SoftContact, NormalForceIsThePenaltyLawSharedByThePairsPoints) {
  sim::ContactSettings c;
  sim::PointState s = touching(Vector3::Zero(), Vector3::Zero());
  const sim::PointForce f = sim::point_force(s, c, sim::FrictionState::kOff, 1e-3);
  EXPECT_NEAR(f.normal_force, c.kp * s.depth / 4, 1e-9);  // eq. 6.14 with n_C = 4
  EXPECT_TRUE(f.force_W.isApprox(f.normal_force * s.normal_W, 1e-12));
}

TEST(SoftContact, NeverPulls) {
  sim::ContactSettings c;
  // leaving fast: kP d − kD u < 0
  sim::PointState s =
      touching(touching(Vector3::Zero(), Vector3::Zero()).normal_W * 1.0, Vector3::Zero());
  EXPECT_EQ(sim::trial_forces(s, c).normal, 0);
  const sim::PointForce f = sim::point_force(s, c, sim::FrictionState::kStick, 1e-3);
  EXPECT_EQ(f.force_W, Vector3::Zero());
  EXPECT_EQ(f.dF_dp, Matrix3::Zero());
  EXPECT_EQ(f.dF_dv, Matrix3::Zero());
}

TEST(SoftContact, StaticFrictionRestoresTowardTheAnchorAndMatchesItsDerivatives) {
  sim::ContactSettings c;
  const Vector3 n = touching(Vector3::Zero(), Vector3::Zero()).normal_W;
  const Vector3 t = n.unitOrthogonal();
  sim::PointState s = touching(1e-4 * t, 1e-4 * t);
  const sim::Trial trial = sim::trial_forces(s, c);
  ASSERT_EQ(sim::pair_friction(&trial, 1, c), sim::FrictionState::kStick);
  const sim::PointForce f = sim::point_force(s, c, sim::FrictionState::kStick, 1e-3);
  EXPECT_TRUE(f.force_W.isApprox(trial.normal * n + trial.friction, 1e-12));
  EXPECT_LT(f.force_W.dot(t), 0);  // pulls the point back toward its anchor
  EXPECT_EQ(f.anchor_W, s.anchor_W);
  Matrix3 dp, dv;
  numeric_derivatives(s, c, sim::FrictionState::kStick, 1e-3, dp, dv);
  EXPECT_TRUE(f.dF_dp.isApprox(dp, 1e-6)) << f.dF_dp << "\n" << dp;
  EXPECT_TRUE(f.dF_dv.isApprox(dv, 1e-6)) << f.dF_dv << "\n" << dv;
}

TEST(SoftContact, DynamicFrictionOpposesTheSlipAndMatchesItsDerivatives) {
  sim::ContactSettings c;
  const Vector3 n = touching(Vector3::Zero(), Vector3::Zero()).normal_W;
  const Vector3 t = n.unitOrthogonal();
  // saturated, on the smooth part of w, and with w's rate set by the pair's load
  for (const double pair_load : {0.0, 2000.0}) {
    for (const double speed : {0.3, 2e-3}) {
      sim::PointState s = touching(speed * t + 0.01 * n.cross(t), 0.1 * t);
      s.pair_normal_force = pair_load;
      const sim::Trial trial = sim::trial_forces(s, c);
      ASSERT_EQ(sim::pair_friction(&trial, 1, c), sim::FrictionState::kSlide) << speed;
      const sim::PointForce f = sim::point_force(s, c, sim::FrictionState::kSlide, 1e-3);
      const Vector3 tangential = f.force_W - f.force_W.dot(n) * n;
      EXPECT_LT(tangential.dot(s.velocity_W), 0);
      EXPECT_LE(tangential.norm(), c.mu_dynamic * f.normal_force * (1 + 1e-12));
      EXPECT_EQ(f.anchor_W, s.position_W);  // the anchor follows a sliding point
      Matrix3 dp, dv;
      numeric_derivatives(s, c, sim::FrictionState::kSlide, 1e-3, dp, dv);
      EXPECT_TRUE(f.dF_dp.isApprox(dp, 1e-5)) << speed << "\n" << f.dF_dp << "\n" << dp;
      EXPECT_TRUE(f.dF_dv.isApprox(dv, 1e-5)) << speed << "\n" << f.dF_dv << "\n" << dv;
    }
  }
}

TEST(SoftContact, APairSticksWhileItsTotalFitsItsTotalCone) {
  sim::ContactSettings c;
  // one unloaded corner over its own cone, the pair within its total: the pair sticks
  const sim::Trial trials[2] = {{10.0, Vector3(3.0, 0, 0)}, {1.0, Vector3(1.0, 0, 0)}};
  EXPECT_GT(trials[1].friction.norm(), c.mu_static * trials[1].normal);
  EXPECT_EQ(sim::pair_friction(trials, 2, c), sim::FrictionState::kStick);
  const sim::Trial over[2] = {{10.0, Vector3(5.0, 0, 0)}, {1.0, Vector3(1.0, 0, 0)}};
  EXPECT_EQ(sim::pair_friction(over, 2, c), sim::FrictionState::kSlide);
}

TEST(SoftContact, SlidingFrictionSaturatesAtMuDynamic) {
  sim::ContactSettings c;
  const Vector3 n = touching(Vector3::Zero(), Vector3::Zero()).normal_W;
  sim::PointState s = touching(5.0 * n.unitOrthogonal(), Vector3::Zero());
  const sim::PointForce f = sim::point_force(s, c, sim::FrictionState::kSlide, 1e-3);
  const Vector3 tangential = f.force_W - f.force_W.dot(n) * n;
  EXPECT_NEAR(tangential.norm(), c.mu_dynamic * f.normal_force, 1e-9 * f.normal_force);
}

}  // namespace
