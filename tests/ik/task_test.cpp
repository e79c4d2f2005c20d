// Tests for ik/task.hpp: the rows a task contributes, its feedback law (desired velocity), the
// error clamp and the task errors.
#include "ik/task.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstring>
#include <numbers>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace ik;
using core::Quaternion;
using core::Vector3;

// A branching tree (free root, spherical, hinge, slider) at a random configuration.
struct Tree {
  std::shared_ptr<const core::Model> model = fixtures::branching_tree();
  core::Data data{*model};
  Eigen::VectorXd q = core::random_configuration(*model, 4);
  core::FrameJacobian scratch{model->nv};
  Tree() { core::compute_joint_jacobians(*model, data, q); }
  int link(const char* name) const { return model->link_index(name); }
};

TEST(Task, RowsFollowTheModeAndTheJoint) {
  const Tree t;
  EXPECT_EQ(task_rows(*t.model, LinkTask{.link = 1, .mode = TaskMode::kPosition}), 3);
  EXPECT_EQ(task_rows(*t.model, LinkTask{.link = 1, .mode = TaskMode::kOrientation}), 3);
  EXPECT_EQ(task_rows(*t.model, LinkTask{.link = 1, .mode = TaskMode::kPose}), 6);
  EXPECT_EQ(task_rows(*t.model, JointReferenceTask{.joint = t.link("ball")}), 3);
  EXPECT_EQ(task_rows(*t.model, JointReferenceTask{.joint = t.link("hinge")}), 1);
  EXPECT_EQ(task_rows(*t.model, JointReferenceTask{.joint = t.link("slider")}), 1);
  EXPECT_STREQ(to_string(kDrag), "drag");
  EXPECT_STREQ(to_string(kPin), "pin");
  EXPECT_STREQ(to_string(TaskMode::kPose), "pose");
}

TEST(Task, PoseRowsAreThePointJacobianAndTheFeedbackLaw) {
  // rows [angular; linear]; ω_d = ω_ref + K log(R_target Rᵀ), ṙ_d = ṙ_ref + K (r_target − r)
  Tree t;
  const int hand = t.link("hand");
  const Vector3 point(0.01, -0.03, 0.02);
  const Vector3 p_W = t.data.X_W[hand] * point;
  const Quaternion R_W(t.data.X_W[hand].R);
  const Quaternion turn(Eigen::AngleAxisd(0.2, Vector3(1, 2, -1).normalized()));
  const LinkTask task{.role = kPin,
                      .link = hand,
                      .p_LinkPoint = point,
                      .target_W = p_W + Vector3(0.03, -0.02, 0.01),
                      .target_R_W = turn * R_W,
                      .velocity_W = Vector3(0.1, 0.2, 0.3),
                      .angular_velocity_W = Vector3(-0.3, 0.1, 0.2),
                      .mode = TaskMode::kPose};
  const double K = 7.0;
  // rows 2..7 of a larger matrix full of stale entries, as in the solver's stacked Jacobian
  Eigen::MatrixXd stacked = Eigen::MatrixXd::Constant(9, t.model->nv, 7.0);
  Eigen::VectorXd v(6);
  fill_link_task(*t.model, t.data, task, K, ErrorClamp{}, stacked.middleRows(2, 6), v);
  const Eigen::MatrixXd J = stacked.middleRows(2, 6);
  EXPECT_TRUE((stacked.topRows(2).array() == 7.0).all());
  EXPECT_TRUE((stacked.bottomRows(1).array() == 7.0).all());

  core::FrameJacobian expected(t.model->nv);
  core::point_jacobian(*t.model, t.data, hand, point, expected);
  EXPECT_TRUE(J.topRows<3>().isApprox(expected.angular, 1e-14));
  EXPECT_TRUE(J.bottomRows<3>().isApprox(expected.linear, 1e-14));
  const Eigen::AngleAxisd axis_angle(turn);
  const Vector3 w_expected = task.angular_velocity_W + K * axis_angle.angle() * axis_angle.axis();
  EXPECT_LT((v.head<3>() - w_expected).norm(), 1e-12);
  EXPECT_LT((v.tail<3>() - (task.velocity_W + K * Vector3(0.03, -0.02, 0.01))).norm(), 1e-12);
}

TEST(Task, OrientationModeFillsOnlyTheAngularRows) {
  Tree t;
  const int wrist = t.link("wrist");
  const LinkTask task{.link = wrist,
                      .target_W = Vector3(5, 5, 5),  // ignored without position rows
                      .target_R_W = Quaternion(t.data.X_W[wrist].R),
                      .mode = TaskMode::kOrientation};
  Eigen::MatrixXd J = Eigen::MatrixXd::Constant(3, t.model->nv, 7.0);  // stale entries
  Eigen::VectorXd v(3);
  fill_link_task(*t.model, t.data, task, 40.0, ErrorClamp{}, J, v);
  core::point_jacobian(*t.model, t.data, wrist, Vector3::Zero(), t.scratch);
  EXPECT_TRUE(J.isApprox(Eigen::MatrixXd(t.scratch.angular), 1e-14));
  EXPECT_LT(v.norm(), 1e-12);  // already at the target orientation
}

TEST(Task, PositionModeFillsOnlyTheLinearRows) {
  Tree t;
  const int hand = t.link("hand");
  const Vector3 point(0.01, 0.02, -0.03);
  const LinkTask task{.link = hand, .p_LinkPoint = point, .target_W = Vector3(0.1, 0.2, 0.3)};
  Eigen::MatrixXd J = Eigen::MatrixXd::Constant(3, t.model->nv, 7.0);  // stale entries
  Eigen::VectorXd v(3);
  fill_link_task(*t.model, t.data, task, 5.0, ErrorClamp{}, J, v);
  core::point_jacobian(*t.model, t.data, hand, point, t.scratch);
  EXPECT_TRUE(J.isApprox(Eigen::MatrixXd(t.scratch.linear), 1e-14));
}

TEST(Task, FeedbackErrorIsClampedPerStep) {
  Tree t;
  const int hand = t.link("hand");
  const Vector3 p_W = t.data.X_W[hand].p;
  const Vector3 far(10, -4, 3);
  const LinkTask task{.link = hand, .target_W = p_W + far};
  const double K = 20.0;
  const ErrorClamp clamp{.position = 0.05, .orientation = 0.5};
  Eigen::MatrixXd J(3, t.model->nv);
  Eigen::VectorXd v(3);
  fill_link_task(*t.model, t.data, task, K, clamp, J, v);
  // the error is shortened to 0.05 m along the same direction
  EXPECT_NEAR(v.norm(), K * 0.05, 1e-12);
  EXPECT_NEAR(v.normalized().dot(far.normalized()), 1.0, 1e-12);
}

TEST(Task, LinkFeedbackShrinksTheErrorByOneMinusKh) {
  // one small step of the least-norm θ̇ meeting the rows: e ← (1 − K h) e to first order
  Tree t;
  const int hand = t.link("hand");
  const Vector3 offset(0.02, 0.01, -0.015);
  const LinkTask task{.link = hand, .target_W = t.data.X_W[hand].p + offset};
  const double K = 10.0, h = 1e-4;
  Eigen::MatrixXd J(3, t.model->nv);
  Eigen::VectorXd v(3);
  fill_link_task(*t.model, t.data, task, K, ErrorClamp{}, J, v);
  const Eigen::VectorXd qdot = J.transpose() * (J * J.transpose()).llt().solve(v);
  const Eigen::VectorXd q1 = core::integrate(*t.model, t.q, qdot, h);
  core::forward_kinematics(*t.model, t.data, q1);
  const double error = link_task_error(t.data, task).position;
  EXPECT_NEAR(error / offset.norm(), 1 - K * h, 1e-6);
}

TEST(Task, OneDofReferenceIsASelectionRowWithClampedFeedback) {
  Tree t;
  const int hinge = t.link("hinge");
  const int iq = t.model->idx_q[hinge], iv = t.model->idx_v[hinge];
  const JointReferenceTask near{.joint = hinge, .q_ref = t.q[iq] + 0.1, .velocity_ref = 0.5};
  Eigen::MatrixXd J = Eigen::MatrixXd::Constant(1, t.model->nv, 9.0);  // overwritten
  Eigen::VectorXd v(1);
  fill_reference_task(*t.model, t.q, near, 3.0, ErrorClamp{}, J, v);
  EXPECT_EQ(J(0, iv), 1.0);
  EXPECT_EQ(J.cwiseAbs().sum(), 1.0);  // every other column zero
  EXPECT_NEAR(v[0], 0.5 + 3.0 * 0.1, 1e-12);
  // far from the reference: the error is clamped to the orientation clamp (rad)
  const JointReferenceTask far{.joint = hinge, .q_ref = t.q[iq] - 4.0};
  fill_reference_task(*t.model, t.q, far, 3.0, ErrorClamp{.orientation = 0.25}, J, v);
  EXPECT_NEAR(v[0], -3.0 * 0.25, 1e-12);
  EXPECT_NEAR(reference_task_error(*t.model, t.q, far).orientation, 4.0, 1e-12);
}

TEST(Task, SphericalReferencePullsEvenAtHalfATurn) {
  // log(Rᵀ R_ref) in the child frame: a 180° error still has a direction (docs/ik.md Q5)
  Tree t;
  const int ball = t.link("ball");
  const int iq = t.model->idx_q[ball], iv = t.model->idx_v[ball];
  const Quaternion R = core::quaternion_at(t.q, iq);
  const Vector3 axis = Vector3(0.3, -1, 0.2).normalized();
  const JointReferenceTask task{.joint = ball,
                                .R_ref = R * Quaternion(Eigen::AngleAxisd(std::numbers::pi, axis))};
  Eigen::MatrixXd J(3, t.model->nv);
  Eigen::VectorXd v(3);
  fill_reference_task(*t.model, t.q, task, 2.0, ErrorClamp{.orientation = 1.0}, J, v);
  EXPECT_TRUE(J.middleCols<3>(iv).isIdentity(0));
  EXPECT_NEAR(v.norm(), 2.0 * 1.0, 1e-9);                      // clamped to 1 rad
  EXPECT_NEAR(std::abs(v.normalized().dot(axis)), 1.0, 1e-9);  // about the error's axis
  EXPECT_NEAR(reference_task_error(*t.model, t.q, task).orientation, std::numbers::pi, 1e-9);
}

TEST(Task, LinkErrorHasOnlyTheModesParts) {
  Tree t;
  core::forward_kinematics(*t.model, t.data, t.q);
  const int hand = t.link("hand");
  const Quaternion R(t.data.X_W[hand].R);
  LinkTask task{.link = hand,
                .target_W = t.data.X_W[hand].p + Vector3(0, 0.3, 0.4),
                .target_R_W = R * Quaternion(Eigen::AngleAxisd(0.25, Vector3::UnitZ()))};
  TaskError e = link_task_error(t.data, task);
  EXPECT_NEAR(e.position, 0.5, 1e-12);
  EXPECT_EQ(e.orientation, 0.0);
  task.mode = TaskMode::kOrientation;
  e = link_task_error(t.data, task);
  EXPECT_EQ(e.position, 0.0);
  EXPECT_NEAR(e.orientation, 0.25, 1e-12);
  task.mode = TaskMode::kPose;
  e = link_task_error(t.data, task);
  EXPECT_NEAR(e.position, 0.5, 1e-12);
  EXPECT_NEAR(e.orientation, 0.25, 1e-12);
}

}  // namespace
