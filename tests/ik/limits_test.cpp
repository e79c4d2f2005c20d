// Tests for ik/limits.hpp: the range rows of 1-DOF limits (Yamane eq. 8.23) and spherical
// swing–twist ranges (§8.3.5), the predictive rows that stop a joint at its boundary, and the
// solver keeping a joint at its limit without chatter.
#include "ik/limits.hpp"

#include <gtest/gtest.h>

#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/swing_twist.hpp"
#include "ik/solver.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace ik;
using core::Quaternion;
using core::Vector3;

// the branching tree's hinge has limits [−1, 2] rad, its slider [−0.2, 0.3] m
struct RangeTree {
  std::shared_ptr<const core::Model> model = fixtures::branching_tree();
  Eigen::VectorXd q = core::neutral_configuration(*model);
  std::vector<RangeRow> rows;
  std::vector<char> flags = std::vector<char>(model->njoints, 0);
  int hinge = model->link_index("hinge");
  int slider = model->link_index("slider");
  double& angle() { return q[model->idx_q[hinge]]; }
};

bool in_range(const core::Model& m, int joint, const Quaternion& r) {
  return core::check_joint_range(m, joint, core::joint_swing_twist(m, joint, r)).inside;
}

TEST(Limits, OneDofJointsOutsideTheirLimitsGetAPullBackRow) {
  RangeTree t;
  t.angle() = 2.3;                        // 0.3 above the upper limit
  t.q[t.model->idx_q[t.slider]] = -0.25;  // 0.05 below the lower limit
  collect_range_violations(*t.model, t.q, 20.0, 5.0, t.rows, t.flags);
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[0].joint, t.hinge);
  EXPECT_EQ(t.rows[0].rows, 1);
  EXPECT_NEAR(t.rows[0].desired[0], 20.0 * (2.0 - 2.3), 1e-12);  // φ̇ = K (φ_max − φ)
  EXPECT_EQ(t.rows[1].joint, t.slider);
  EXPECT_NEAR(t.rows[1].desired[0], 20.0 * 0.05, 1e-12);  // K (φ_min − φ) > 0
  EXPECT_TRUE(t.flags[t.hinge]);
  EXPECT_TRUE(t.flags[t.slider]);
  EXPECT_NEAR(max_range_violation(*t.model, t.q), 0.3, 1e-12);
}

TEST(Limits, JointsInsideTheirRangesGetNoRows) {
  RangeTree t;
  t.angle() = 1.999;
  collect_range_violations(*t.model, t.q, 20.0, 5.0, t.rows, t.flags);
  EXPECT_TRUE(t.rows.empty());
  EXPECT_EQ(max_range_violation(*t.model, t.q), 0.0);
}

TEST(Limits, PredictedCrossingStopsTheJointInsideTheMargin) {
  RangeTree t;
  t.angle() = 1.9;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(t.model->nv);
  const int iv = t.model->idx_v[t.hinge];
  const double h = 0.1, margin = 0.01;
  // moving away from the limit: no row
  v[iv] = -5.0;
  EXPECT_EQ(collect_range_predictions(*t.model, t.q, v, h, margin, t.rows, t.flags), 0);
  // moving toward it fast enough to cross within h: a row that ends the step at 2 − margin
  v[iv] = 5.0;
  EXPECT_EQ(collect_range_predictions(*t.model, t.q, v, h, margin, t.rows, t.flags), 1);
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_NEAR(t.angle() + h * t.rows[0].desired[0], 2.0 - margin, 1e-12);
  EXPECT_TRUE(t.flags[t.hinge]);
  // a flagged joint is not predicted again in a later round
  EXPECT_EQ(collect_range_predictions(*t.model, t.q, v, h, margin, t.rows, t.flags), 0);
}

TEST(Limits, JointInsideTheMarginBandIsHeldNotPushedBack) {
  RangeTree t;
  t.angle() = 2.0 - 0.005;  // already closer than the 0.01 margin
  Eigen::VectorXd v = Eigen::VectorXd::Zero(t.model->nv);
  v[t.model->idx_v[t.hinge]] = 1.0;
  ASSERT_EQ(collect_range_predictions(*t.model, t.q, v, 0.1, 0.01, t.rows, t.flags), 1);
  EXPECT_EQ(t.rows[0].desired[0], 0.0);
}

TEST(Limits, SphericalJointOutsideItsRangeIsPulledTowardItsStandardOrientation) {
  const auto model = core::build_human_figure({});
  const int shoulder = model->link_index("r_uarm");
  ASSERT_FALSE(model->spherical_range[shoulder].empty());
  Eigen::VectorXd q = core::neutral_configuration(*model);
  const Quaternion r(Eigen::AngleAxisd(2.5, Vector3::UnitY()));
  core::set_quaternion_at(q, model->idx_q[shoulder], r);
  ASSERT_FALSE(in_range(*model, shoulder, r));
  std::vector<RangeRow> rows;
  std::vector<char> flags(model->njoints, 0);
  collect_range_violations(*model, q, 20.0, 5.0, rows, flags);
  const auto it = std::find_if(rows.begin(), rows.end(),
                               [&](const RangeRow& row) { return row.joint == shoulder; });
  ASSERT_NE(it, rows.end());
  EXPECT_EQ(it->rows, 3);
  // ω = K log(Rᵀ R_S) in the child frame (range gain 5)
  const Vector3 expected =
      5.0 * core::quaternion_log(r.conjugate() * model->standard_orientation[shoulder]);
  EXPECT_LT((it->desired - expected).norm(), 1e-12);
  EXPECT_GT(max_range_violation(*model, q), 0.0);
}

TEST(Limits, SphericalJointAboutToLeaveItsRangeIsHeld) {
  const auto model = core::build_human_figure({});
  const int hip = model->link_index("r_thigh");
  ASSERT_FALSE(model->spherical_range[hip].empty());
  Eigen::VectorXd q = core::neutral_configuration(*model);
  const Quaternion r = model->standard_orientation[hip];
  core::set_quaternion_at(q, model->idx_q[hip], r);
  ASSERT_TRUE(in_range(*model, hip, r));
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model->nv);
  const double h = 0.1;
  v.segment<3>(model->idx_v[hip]) = Vector3(0, 0, 30.0);  // 3 rad in one step
  ASSERT_FALSE(in_range(*model, hip, r * core::quaternion_exp(Vector3(0, 0, 3.0))));
  std::vector<RangeRow> rows;
  std::vector<char> flags(model->njoints, 0);
  EXPECT_EQ(collect_range_predictions(*model, q, v, h, 1e-3, rows, flags), 1);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].joint, hip);
  EXPECT_EQ(rows[0].rows, 3);
  EXPECT_EQ(rows[0].desired, Vector3::Zero());
}

TEST(Limits, JointLimitsAreRespectedWithoutChatter) {
  // drive the hinge against its upper limit (2.0 rad) with a reference beyond it
  const auto model = fixtures::branching_tree();
  core::Data data(*model);
  Eigen::VectorXd q = core::neutral_configuration(*model);
  const int hinge = model->link_index("hinge");
  Problem p;
  p.add(JointReferenceTask{.joint = hinge, .q_ref = 3.0, .gain = 5.0});
  Solver solver(*model);
  double previous = q[model->idx_q[hinge]];
  for (int k = 0; k < 200; ++k) {
    solver.step(p, data, q);
    const double angle = q[model->idx_q[hinge]];
    // the range rows outweigh the reference 1000:1, so the limit gives way by < 1e-3 rad
    EXPECT_LE(angle, 2.0 + 1e-3) << k;
    // no chatter: the joint approaches the limit monotonically and stays there
    EXPECT_GE(angle, previous - 1e-12) << k;
    previous = angle;
  }
  EXPECT_GT(previous, 2.0 - 2 * kDefaultLimitMargin);
}

}  // namespace
