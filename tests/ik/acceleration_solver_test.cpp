// Tests for ik/acceleration_solver.hpp: the acceleration-level pin-and-drag solver in the
// floating-base form (Yamane ch. 9, digest §2.8).
#include "ik/acceleration_solver.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/rnea.hpp"
#include "tests/fixtures/allocation_counter.hpp"

namespace {

using core::Vector3;

// the human figure in its rest pose, moving, with contact wrenches on both feet
struct HumanScene {
  std::shared_ptr<const core::Model> model = core::build_human_figure({});
  core::Data data{*model};
  Eigen::VectorXd q, v, bias, contact;
  std::vector<core::Force> f_ext;
  ik::Problem problem;
  int drag = 0;

  explicit HumanScene(bool with_contact) {
    const core::Model& m = *model;
    q = core::rest_configuration(m);
    v = 0.3 * core::difference(m, q, core::random_configuration(m, 7));
    core::forward_kinematics(m, data, q, v);
    f_ext.assign(m.njoints, core::Force::Zero());
    contact = Eigen::VectorXd::Zero(m.nv);
    if (with_contact) {
      core::compute_joint_jacobians(m, data);
      for (const char* foot : {"l_foot", "r_foot"}) {
        const int l = m.link_index(foot);
        const Vector3 p = data.X_W[l] * Vector3(0.01, -0.05, 0.03);
        const Vector3 f(12.0, 340.0, -8.0), n(1.5, 0.3, -2.0);
        f_ext[l] = core::link_force_from_world(data, l, f, p, n);
        core::FrameJacobian J(m.nv);
        core::point_jacobian(m, data, l, data.X_W[l].inverse_apply(p), J);
        contact += J.angular.transpose() * n + J.linear.transpose() * f;
      }
    }
    // a drag on the left hand (top), weak orientation pins on the feet, references on the spine
    const int hand = m.link_index("l_hand");
    ik::LinkTask d{.role = ik::kDrag, .link = hand};
    d.target_W = data.X_W[hand].p + Vector3(0, -0.06, 0.03);  // inside the error clamp
    drag = problem.add(d);
    for (const char* foot : {"l_foot", "r_foot"}) {
      const int l = m.link_index(foot);
      ik::LinkTask pin{.role = ik::kPin, .link = l};
      pin.mode = ik::TaskMode::kOrientation;
      pin.target_R_W = core::Quaternion(data.X_W[l].R);
      pin.weight = 0.1;
      problem.add(pin);
    }
    for (const char* joint : {"abdomen", "chest", "neck"}) {
      ik::JointReferenceTask r{.joint = m.link_index(joint)};
      problem.add(r);
    }
    prepare();
  }

  void prepare() {
    const core::Model& m = *model;
    core::forward_kinematics(m, data, q, v);
    core::compute_joint_jacobians(m, data);
    bias = core::bias_forces(m, data, q, v);
    core::crba(m, data, q);
    core::forward_kinematics(m, data, q, v);  // rnea and crba overwrite some fields
    core::compute_joint_jacobians(m, data);
  }
};

TEST(AccelerationSolver, RootRowsAreMetByTheContactForcesAlone) {
  for (const bool with_contact : {false, true}) {
    HumanScene s(with_contact);
    ik::AccelerationSolver solver(*s.model);
    const ik::AccelerationReport& r = solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
    ASSERT_EQ(r.status, ik::AccelerationReport::Status::kOk) << r.message;
    EXPECT_LT(r.root_residual, 1e-9);
    EXPECT_TRUE(solver.torque().head<6>().isZero(0));
    EXPECT_TRUE(solver.acceleration().allFinite());
  }
}

TEST(AccelerationSolver, ForwardDynamicsWithTheTorquesReproducesTheAccelerations) {
  HumanScene s(true);
  ik::AccelerationSolver solver(*s.model);
  solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  core::Data fd(*s.model);
  const Eigen::VectorXd a = core::aba(*s.model, fd, s.q, s.v, solver.torque(), s.f_ext);
  EXPECT_LT((a - solver.acceleration()).norm(), 1e-9 * (1 + a.norm()));
}

// A drag the joints cannot follow (a stiff gain on a far target) is cut to the bounds of the
// settings; the root rows still hold, so the cut costs the drag, never the physics.
TEST(AccelerationSolver, JointAccelerationsAndSpeedsStayWithinTheirBounds) {
  HumanScene s(true);
  s.problem.get<ik::LinkTask>(s.drag)->gain = 400;  // ω: 1.6e5 × 0.06 m ≈ 1e4 m/s² asked
  ik::AccelerationSettings settings;
  settings.max_joint_acceleration = 150;
  settings.max_joint_speed = 3;
  ik::AccelerationSolver solver(*s.model, settings);
  const ik::AccelerationReport& r = solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  ASSERT_EQ(r.status, ik::AccelerationReport::Status::kOk) << r.message;
  EXPECT_TRUE(r.bounded);
  const Eigen::VectorXd qdd = solver.acceleration().tail(s.model->nv - 6);
  EXPECT_LE(qdd.cwiseAbs().maxCoeff(), 150 + 1e-9);
  const Eigen::VectorXd v_next = s.v.tail(s.model->nv - 6) + settings.step * qdd;
  EXPECT_LE(v_next.cwiseAbs().maxCoeff(),
            std::max(3.0, s.v.tail(s.model->nv - 6).cwiseAbs().maxCoeff()) + 1e-9);
  EXPECT_LT(r.root_residual, 1e-9);
  // the same problem at its default gain is within the bounds and left alone
  s.problem.get<ik::LinkTask>(s.drag)->gain = ik::kDefaultGain;
  EXPECT_FALSE(ik::AccelerationSolver(*s.model)
                   .solve(s.problem, s.data, s.q, s.v, s.bias, s.contact)
                   .bounded);
}

TEST(AccelerationSolver, TheDraggedPointAcceleratesAsCommanded) {
  HumanScene s(true);
  ik::AccelerationSolver solver(*s.model);
  solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  const core::Model& m = *s.model;
  const ik::LinkTask& d = *s.problem.get<ik::LinkTask>(s.drag);
  // r̈ᵈ = K_v (ṙ_ref − ṙ) + K_p (r_ref − r), ω = 10: K_p = 100, K_v = 20
  const core::PointMotion vel = core::point_velocity(m, s.data, d.link, d.p_LinkPoint);
  const Vector3 p = s.data.X_W[d.link] * d.p_LinkPoint;
  const Vector3 desired = 20.0 * (Vector3::Zero() - vel.linear) + 100.0 * (d.target_W - p);
  core::Data fk(m);
  core::forward_kinematics(m, fk, s.q, s.v, solver.acceleration());
  const Vector3 achieved = core::point_acceleration(m, fk, d.link, d.p_LinkPoint).linear;
  EXPECT_LT((achieved - desired).norm(), 1e-9 * (1 + desired.norm()))
      << achieved.transpose() << " vs " << desired.transpose();
}

TEST(AccelerationSolver, DoesNotAllocateOnceSized) {
  HumanScene s(true);
  ik::AccelerationSolver solver(*s.model);
  solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  fixtures::AllocationCounter allocations;
  Eigen::internal::set_is_malloc_allowed(false);
  for (int k = 0; k < 3; ++k) solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.count(), 0);
}

TEST(AccelerationSolver, RefusesAFixedRootAndTooManyDragRows) {
  HumanScene s(false);
  ik::AccelerationSolver solver(*s.model);
  for (int k = 0; k < 2; ++k) {
    ik::LinkTask d{.role = ik::kDrag, .link = s.model->link_index("r_hand")};
    d.mode = ik::TaskMode::kPose;
    s.problem.add(d);
  }
  const auto& r = solver.solve(s.problem, s.data, s.q, s.v, s.bias, s.contact);
  EXPECT_EQ(r.status, ik::AccelerationReport::Status::kRejected);
  EXPECT_NE(r.message.find("at most 12"), std::string::npos) << r.message;
}

}  // namespace
