// Tests for core/configuration.hpp.
#include "core/configuration.hpp"

#include <gtest/gtest.h>

#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;

// q and q' describe the same configuration (quaternions up to sign)
void expect_same_configuration(const Model& m,
                               const Eigen::VectorXd& a,
                               const Eigen::VectorXd& b,
                               double tol) {
  Eigen::VectorXd d = difference(m, a, b);
  EXPECT_LT(d.cwiseAbs().maxCoeff(), tol);
}

TEST(Configuration, NeutralHasIdentityRotations) {
  const auto m = fixtures::branching_tree();
  const Eigen::VectorXd q = neutral_configuration(*m);
  EXPECT_EQ(q.size(), m->nq);
  EXPECT_EQ(check_configuration(*m, q), "");
  EXPECT_EQ(q[3], 1.0);  // free root quaternion w
}

TEST(Configuration, IntegrateOfDifferenceReachesTheTarget) {
  const auto m = fixtures::branching_tree();
  for (std::uint64_t seed = 1; seed < 50; ++seed) {
    const Eigen::VectorXd q0 = random_configuration(*m, seed);
    const Eigen::VectorXd q1 = random_configuration(*m, seed + 1000);
    const Eigen::VectorXd v = difference(*m, q0, q1);
    const Eigen::VectorXd q = integrate(*m, q0, v, 1.0);
    // exactly q1 up to rounding, with quaternions in q1's hemisphere or the opposite one
    for (int i = 1; i < m->njoints; ++i) {
      const int iq = m->idx_q[i];
      const int n = joint_nq(m->joint_type[i]);
      const bool has_quat =
          m->joint_type[i] == JointType::kSpherical || m->joint_type[i] == JointType::kFree;
      const int qi = m->joint_type[i] == JointType::kFree ? iq + 3 : iq;
      if (m->joint_type[i] == JointType::kFree) {
        EXPECT_TRUE(q.segment<3>(iq).isApprox(q1.segment<3>(iq), 1e-10));
      }
      if (has_quat) {
        const double s = q.segment<4>(qi).dot(q1.segment<4>(qi)) < 0 ? -1.0 : 1.0;
        EXPECT_LT((s * q.segment<4>(qi) - q1.segment<4>(qi)).norm(), 1e-12);
      } else {
        EXPECT_NEAR((q.segment(iq, n) - q1.segment(iq, n)).norm(), 0.0, 1e-12);
      }
    }
  }
}

TEST(Configuration, DifferenceOfIntegrateRecoversTheVelocity) {
  const auto m = fixtures::branching_tree();
  const Eigen::VectorXd q0 = random_configuration(*m, 7);
  Eigen::VectorXd v(m->nv);
  for (int k = 0; k < m->nv; ++k) v[k] = 0.1 * (k % 5) - 0.2;
  EXPECT_TRUE(difference(*m, q0, integrate(*m, q0, v, 1.0)).isApprox(v, 1e-10));
}

TEST(Configuration, IntegrationComposesForConstantVelocity) {
  // the exponential map: two half steps equal one full step
  const auto m = fixtures::branching_tree();
  const Eigen::VectorXd q0 = random_configuration(*m, 3);
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(m->nv, -1.0, 1.5);
  const Eigen::VectorXd half = integrate(*m, integrate(*m, q0, v, 0.5), v, 0.5);
  expect_same_configuration(*m, half, integrate(*m, q0, v, 1.0), 1e-12);
}

TEST(Configuration, RandomConfigurationsAreValidAndRepeatable) {
  const auto m = fixtures::branching_tree();
  for (std::uint64_t seed = 0; seed < 100; ++seed) {
    const Eigen::VectorXd q = random_configuration(*m, seed);
    EXPECT_EQ(check_configuration(*m, q, 1e-12), "");
    EXPECT_EQ(q, random_configuration(*m, seed));
    const int hinge = m->link_index("hinge");
    EXPECT_GE(q[m->idx_q[hinge]], -1.0);
    EXPECT_LE(q[m->idx_q[hinge]], 2.0);
  }
  EXPECT_NE(random_configuration(*m, 1), random_configuration(*m, 2));
}

TEST(Configuration, CheckNamesTheOffendingJoint) {
  const auto m = fixtures::branching_tree();
  Eigen::VectorXd q = neutral_configuration(*m);
  q[m->idx_q[m->link_index("ball")]] = 2.0;
  EXPECT_NE(check_configuration(*m, q).find("joint 'ball'"), std::string::npos);
  q = neutral_configuration(*m);
  q[m->idx_q[m->link_index("hinge")]] = NAN;
  EXPECT_NE(check_configuration(*m, q).find("joint 'hinge': configuration is not finite"),
            std::string::npos);
  EXPECT_NE(check_configuration(*m, Eigen::VectorXd(3)).find("needs"), std::string::npos);
}

TEST(Configuration, IntegrateAndDifferenceDoNotAllocate) {
  const auto m = fixtures::branching_tree();
  Eigen::VectorXd q = random_configuration(*m, 5);
  const Eigen::VectorXd q1 = random_configuration(*m, 6);
  Eigen::VectorXd v(m->nv);
  fixtures::AllocationCounter allocations;
  difference(*m, q, q1, v);
  integrate(*m, q, v, 0.01, q);
  EXPECT_EQ(allocations.count(), 0);
}

}  // namespace
