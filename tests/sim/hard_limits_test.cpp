// The hard_limits effect: joints stop at their limits (sim/world_limits.cpp).
#include <gtest/gtest.h>

#include "core/centroidal.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "core/swing_twist.hpp"
#include "ik/limits.hpp"
#include "sim/world.hpp"

namespace {

// a pendulum on a hinge about z (limits ±0.5 rad) carrying a second one (±1 rad), both swinging
std::shared_ptr<const core::Model> double_pendulum() {
  core::ModelBuilder b("pendulum");
  for (int i = 0; i < 2; ++i) {
    core::LinkSpec l;
    l.name = "arm" + std::to_string(i);
    l.parent = i == 0 ? "" : "arm0";
    l.joint.type = core::JointType::kRevolute;
    l.joint.axis = core::Vector3::UnitZ();
    l.joint.X_PJ = core::Transform::from_translation(core::Vector3(0, i == 0 ? 0 : -0.5, 0));
    l.joint.limits = i == 0 ? core::JointLimits{-0.5, 0.5} : core::JointLimits{-1.0, 1.0};
    l.mass = 1;
    l.com = core::Vector3(0, -0.25, 0);
    l.I_com = core::Matrix3::Identity() * 0.02;
    b.add_link(l);
  }
  return b.finalize();
}

// a rod on a ball joint with a 30° cone about its nominal direction (down)
std::shared_ptr<const core::Model> cone_rod() {
  core::ModelBuilder b("rod");
  core::LinkSpec l;
  l.name = "rod";
  l.joint.type = core::JointType::kSpherical;
  l.joint.range = core::cone_range(M_PI / 6, -0.3, 0.3);
  l.joint.range.frame =
      core::Quaternion::FromTwoVectors(core::Vector3::UnitX(), -core::Vector3::UnitY());
  l.mass = 2;
  l.com = core::Vector3(0, -0.4, 0);
  l.I_com = core::Matrix3::Identity() * 0.05;
  b.add_link(l);
  return b.finalize();
}

TEST(HardLimits, AJointThatHitsItsLimitStopsThereAndNeverCrossesIt) {
  auto m = double_pendulum();
  sim::World w;
  Eigen::VectorXd v(2);
  v << 3.0, -4.0;
  w.add_body("pendulum", m, core::neutral_configuration(*m), v);
  sim::Scene s;
  s.gravity = s.hard_limits = true;
  w.set_scene(s);
  int impacts = 0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::VectorXd v_before = w.body(0).v;
    w.step();
    const Eigen::VectorXd& q = w.body(0).q;
    const Eigen::VectorXd& vel = w.body(0).v;
    for (int j = 0; j < 2; ++j) {
      const core::JointLimits& L = m->limits[j + 1];
      ASSERT_LE(q[j], L.upper) << "step " << k;
      ASSERT_GE(q[j], L.lower) << "step " << k;
      // on its limit, a joint never moves further into it
      if (q[j] == L.upper) {
        EXPECT_LE(vel[j], 1e-12) << "step " << k;
        impacts += v_before[j] > 0;
      }
      if (q[j] == L.lower) {
        EXPECT_GE(vel[j], -1e-12) << "step " << k;
        impacts += v_before[j] < 0;
      }
    }
  }
  EXPECT_GT(impacts, 1);
}

TEST(HardLimits, ImpulsesKeepTheMomentumOfTheRest) {
  // a free-floating two-link body without gravity: stopping a joint must not change the total
  // linear momentum (the impulse is internal, through H⁻¹); fine steps keep the integrator's own
  // drift far below the 1e-4 checked here
  core::ModelBuilder b("floating");
  core::LinkSpec base;
  base.name = "base";
  base.joint.type = core::JointType::kFree;
  base.mass = 3;
  base.I_com = core::Matrix3::Identity() * 0.1;
  b.add_link(base);
  core::LinkSpec arm;
  arm.name = "arm";
  arm.parent = "base";
  arm.joint.type = core::JointType::kRevolute;
  arm.joint.limits = {-0.2, 0.2};
  arm.joint.X_PJ = core::Transform::from_translation(core::Vector3(0.3, 0, 0));
  arm.mass = 1;
  arm.com = core::Vector3(0.3, 0, 0);
  arm.I_com = core::Matrix3::Identity() * 0.02;
  b.add_link(arm);
  auto m = b.finalize();
  sim::WorldSettings fine;
  fine.step = 1e-5;
  sim::World w(fine);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(m->nv);
  v[6] = 5.0;
  w.add_body("floating", m, core::neutral_configuration(*m), v);
  sim::Scene s;
  s.hard_limits = true;
  w.set_scene(s);
  auto momentum = [&] {
    core::Data d(*m);
    core::forward_kinematics(*m, d, w.body(0).q, w.body(0).v);
    return core::centroidal_momentum(*m, d).linear;
  };
  const core::Vector3 p0 = momentum();
  bool hit = false;
  for (int k = 0; k < 10000; ++k) {
    w.step();
    if (w.body(0).q[7] == 0.2) {
      hit = true;
      EXPECT_LE(w.body(0).v[6], 1e-12);
    }
  }
  EXPECT_TRUE(hit);
  EXPECT_LT((momentum() - p0).norm(), 1e-4 * p0.norm())
      << momentum().transpose() << " vs " << p0.transpose();
}

TEST(HardLimits, ABallJointStaysInsideItsSwingTwistRange) {
  auto m = cone_rod();
  sim::World w;
  Eigen::VectorXd v(3);
  v << 2.0, 0.5, 3.0;
  w.add_body("rod", m, core::neutral_configuration(*m), v);
  sim::Scene s;
  s.gravity = s.hard_limits = true;
  w.set_scene(s);
  double worst = 0;
  for (int k = 0; k < 3000; ++k) {
    w.step();
    worst = std::max(worst, ik::max_range_violation(*m, w.body(0).q));
  }
  EXPECT_EQ(worst, 0.0);
}

}  // namespace
