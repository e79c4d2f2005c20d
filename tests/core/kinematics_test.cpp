// Tests for core/kinematics.hpp, core/jacobian.hpp and core/com.hpp: Jacobians, J̇v and the COM
// Jacobian against finite differences along integrate().
#include "core/kinematics.hpp"

#include <gtest/gtest.h>

#include "core/com.hpp"
#include "core/configuration.hpp"
#include "core/jacobian.hpp"
#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/kinematics_checks.hpp"

namespace {

using namespace core;

TEST(Kinematics, ChainPosesFollowThePlacements) {
  const auto m = fixtures::chain(3);
  Data d(*m);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(3);
  forward_kinematics(*m, d, q);
  EXPECT_TRUE(d.X_W[3].p.isApprox(Vector3(0, 0, 0.2)));
  // link0 turns about z: the chain stays on the z axis, link frames rotate
  q << std::numbers::pi / 2, 0, 0;
  forward_kinematics(*m, d, q);
  EXPECT_TRUE(d.X_W[1].R.col(0).isApprox(Vector3::UnitY(), 1e-15));
  // link1 turns about y by 90°: link2 swings from +z to +x of link1's frame
  q << 0, std::numbers::pi / 2, 0;
  forward_kinematics(*m, d, q);
  EXPECT_TRUE(d.X_W[3].p.isApprox(Vector3(0.1, 0, 0.1), 1e-14));
}

TEST(Kinematics, JacobiansMatchFiniteDifferencesOnTheTree) {
  const auto m = fixtures::branching_tree();
  for (std::uint64_t seed = 0; seed < 10; ++seed) {
    fixtures::expect_jacobians_match_finite_differences(*m, random_configuration(*m, seed), 1e-7);
  }
}

TEST(Kinematics, JdotVMatchesFiniteDifferencesOnTheTree) {
  const auto m = fixtures::branching_tree();
  for (std::uint64_t seed = 0; seed < 10; ++seed) {
    const Eigen::VectorXd q = random_configuration(*m, seed);
    const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, seed + 100));
    fixtures::expect_jdot_v_matches_finite_differences(*m, q, v, 1e-6);
  }
}

TEST(Kinematics, VelocitiesAndAccelerationsAgreeWithJacobians) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const Eigen::VectorXd q = random_configuration(*m, 11);
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(m->nv, -1, 1);
  const Eigen::VectorXd a = Eigen::VectorXd::LinSpaced(m->nv, 2, -0.5);
  forward_kinematics(*m, d, q, v, a);
  compute_joint_jacobians(*m, d);
  FrameJacobian J(m->nv);
  const Vector3 p(0.01, -0.03, 0.02);
  for (int link = 1; link < m->njoints; ++link) {
    point_jacobian(*m, d, link, p, J);
    const PointMotion vel = point_velocity(*m, d, link, p);
    EXPECT_TRUE(vel.angular.isApprox(J.angular * v, 1e-12) || vel.angular.norm() < 1e-14);
    EXPECT_TRUE(vel.linear.isApprox(J.linear * v, 1e-12));
    // p̈ = J a + J̇ v
    const PointMotion acc = point_acceleration(*m, d, link, p);
    const PointMotion jdv = point_jdot_v(*m, d, link, p);
    EXPECT_TRUE(acc.linear.isApprox(J.linear * a + jdv.linear, 1e-12));
    EXPECT_TRUE(acc.angular.isApprox(J.angular * a + jdv.angular, 1e-12) ||
                acc.angular.norm() < 1e-14);
  }
}

TEST(Kinematics, LinkJacobiansMatchPointJacobiansAcrossUpdates) {
  for (const auto& m : {fixtures::branching_tree(), fixtures::chain(5)}) {
    std::vector<LinkJacobians::Point> points;
    for (int link = 1; link < m->njoints; ++link) {
      points.push_back({link, Vector3(0.02 * link, -0.03, 0.01)});
      points.push_back({link, Vector3::Zero()});
    }
    LinkJacobians jacobians(*m, points);
    ASSERT_EQ(jacobians.size(), static_cast<int>(points.size()));
    Data d(*m);
    FrameJacobian expected(m->nv);
    // successive configurations: each update must leave exactly the fresh Jacobian, with every
    // column off the link's root path still zero
    for (std::uint64_t seed = 0; seed < 4; ++seed) {
      compute_joint_jacobians(*m, d, random_configuration(*m, seed));
      jacobians.update(*m, d);
      for (int k = 0; k < jacobians.size(); ++k) {
        point_jacobian(*m, d, points[k].link, points[k].p_LinkPoint, expected);
        EXPECT_EQ(jacobians[k].angular, expected.angular) << "point " << k << ", seed " << seed;
        EXPECT_EQ(jacobians[k].linear, expected.linear) << "point " << k << ", seed " << seed;
      }
    }
  }
}

TEST(Kinematics, LinkJacobiansRefuseAPointOffTheModel) {
  const auto m = fixtures::chain(3);
  for (int bad : {0, -1, m->njoints}) {
    try {
      LinkJacobians jacobians(*m, {{1, Vector3::Zero()}, {bad, Vector3::Zero()}});
      ADD_FAILURE() << "link " << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("point 1 is on link " + std::to_string(bad)),
                std::string::npos)
          << e.what();
    }
  }
}

TEST(Kinematics, ComJacobianMatchesFiniteDifferences) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const Eigen::VectorXd q = random_configuration(*m, 4);
  compute_joint_jacobians(*m, d, q);
  const Matrix3X Jc = com_jacobian(*m, d);
  EXPECT_NEAR(d.mass, m->total_mass(), 1e-12);
  const double h = 1e-6;
  for (int k = 0; k < m->nv; ++k) {
    Eigen::VectorXd dv = Eigen::VectorXd::Zero(m->nv);
    dv[k] = h;
    Data dp(*m), dm(*m);
    forward_kinematics(*m, dp, integrate(*m, q, dv, 1.0));
    forward_kinematics(*m, dm, integrate(*m, q, dv, -1.0));
    const Vector3 fd = (center_of_mass(*m, dp) - center_of_mass(*m, dm)) / (2 * h);
    EXPECT_LT((fd - Jc.col(k)).norm(), 1e-8) << "column " << k;
  }
}

TEST(Kinematics, PerStepPathDoesNotAllocate) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const Eigen::VectorXd q = random_configuration(*m, 1);
  const Eigen::VectorXd v = Eigen::VectorXd::Ones(m->nv);
  FrameJacobian J(m->nv);
  LinkJacobians all_links(*m, {{1, Vector3::Zero()}, {3, Vector3(0.1, 0, 0)}});
  fixtures::AllocationCounter allocations;
  Eigen::internal::set_is_malloc_allowed(false);
  forward_kinematics(*m, d, q, v, v);
  compute_joint_jacobians(*m, d, q);
  point_jacobian(*m, d, 3, Vector3(0.1, 0, 0), J);
  all_links.update(*m, d);
  com_jacobian(*m, d);
  const PointMotion jdv = point_jdot_v(*m, d, 3, Vector3::Zero());
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.count(), 0);
  EXPECT_TRUE(jdv.linear.allFinite());
}

}  // namespace
