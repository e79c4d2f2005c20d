// Tests for core/osim.hpp: the sparse Φ against J H⁻¹ Jᵀ formed densely, and the floating-base
// split of digest §2.8.
#include "core/osim.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/kinematics.hpp"
#include "core/rnea.hpp"
#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;

std::vector<Handle> tree_handles(const Model& m) {
  return {{m.link_index("hand"), Vector3(0.01, -0.05, 0.02), true},
          {m.link_index("wrist"), Vector3(0, 0, 0.06), false},
          {m.link_index("base"), Vector3(0.1, 0, 0), true}};
}

TEST(Osim, HandleJacobianStacksThePointJacobians) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const auto handles = tree_handles(*m);
  Eigen::MatrixXd J = Eigen::MatrixXd::Constant(15, m->nv, 7.0);  // stale entries, right size
  FrameJacobian expected(m->nv);
  for (std::uint64_t seed = 0; seed < 3; ++seed) {
    compute_joint_jacobians(*m, d, random_configuration(*m, seed));
    handle_jacobian(*m, d, handles, J);
    ASSERT_EQ(J.rows(), 15);
    int row = 0;
    for (const Handle& h : handles) {
      point_jacobian(*m, d, h.link, h.p_LinkPoint, expected);
      if (h.with_orientation) {
        EXPECT_EQ(Eigen::MatrixXd(J.middleRows(row, 3)), Eigen::MatrixXd(expected.angular));
        row += 3;
      }
      EXPECT_EQ(Eigen::MatrixXd(J.middleRows(row, 3)), Eigen::MatrixXd(expected.linear));
      row += 3;
    }
  }
}

TEST(Osim, SparsePhiEqualsDenseJHinvJt) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const auto handles = tree_handles(*m);
  for (std::uint64_t seed = 0; seed < 5; ++seed) {
    const Eigen::VectorXd q = random_configuration(*m, seed);
    compute_joint_jacobians(*m, d, q);
    const Eigen::MatrixXd H = crba(*m, d, q);
    factorize_mass_matrix(*m, d);
    OsimWorkspace ws;
    Eigen::MatrixXd Phi;
    inverse_operational_inertia(*m, d, handles, ws, Phi);
    const Eigen::MatrixXd dense = ws.J * H.llt().solve(ws.J.transpose());
    EXPECT_LT((Phi - dense).norm(), 1e-10 * dense.norm()) << seed;
    // allocation-free once the workspace is sized
    fixtures::AllocationCounter allocations;
    inverse_operational_inertia(*m, d, handles, ws, Phi);
    EXPECT_EQ(allocations.count(), 0);
  }
}

TEST(Osim, LambdaInvertsPhiAndStaysDefinedWhenSingular) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const Eigen::VectorXd q = random_configuration(*m, 1);
  compute_joint_jacobians(*m, d, q);
  crba(*m, d, q);
  factorize_mass_matrix(*m, d);
  OsimWorkspace ws;
  Eigen::MatrixXd Phi, Lambda;
  // one 6-D handle: Φ is SPD and Λ Φ = E
  inverse_operational_inertia(*m, d, {{m->link_index("hand"), Vector3::Zero(), true}}, ws, Phi);
  EXPECT_EQ(operational_inertia(Phi, Lambda), 6);
  EXPECT_LT((Lambda * Phi - Eigen::MatrixXd::Identity(6, 6)).norm(), 1e-8);
  // the same point twice: Φ is singular, Λ is its pseudoinverse (Φ Λ Φ = Φ, Λ symmetric)
  const Handle h{m->link_index("hand"), Vector3(0.01, 0, 0), false};
  inverse_operational_inertia(*m, d, {h, h}, ws, Phi);
  EXPECT_EQ(operational_inertia(Phi, Lambda), 3);
  EXPECT_TRUE(Lambda.allFinite());
  EXPECT_LT((Phi * Lambda * Phi - Phi).norm(), 1e-9 * Phi.norm());
  EXPECT_LT((Lambda - Lambda.transpose()).norm(), 1e-9 * Lambda.norm());
}

TEST(Osim, FloatingBaseSplitIdentity) {
  // J H⁻¹ Jᵀ = Φ^lock + Γ [H⁻¹ Jᵀ]_q   (digest §2.8, checked numerically in digest-check App. A)
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const auto handles = tree_handles(*m);
  const Eigen::VectorXd q = random_configuration(*m, 8);
  const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, 9));
  forward_kinematics(*m, d, q, v);
  compute_joint_jacobians(*m, d);
  const Eigen::VectorXd b = bias_forces(*m, d, q, v);
  const Eigen::MatrixXd H = crba(*m, d, q);
  FloatingBaseSplit split;
  floating_base_split(*m, d, handles, b, split);
  OsimWorkspace ws;
  Eigen::MatrixXd J;
  handle_jacobian(*m, d, handles, J);
  const Eigen::MatrixXd HinvJt = H.llt().solve(J.transpose());
  const Eigen::MatrixXd lhs = J * HinvJt;
  const Eigen::MatrixXd rhs = split.Phi_lock + split.Gamma * HinvJt.bottomRows(m->nv - 6);
  EXPECT_LT((lhs - rhs).norm(), 1e-10 * lhs.norm());
  EXPECT_TRUE(split.H_bb.isApprox(H.topLeftCorner<6, 6>()));

  // r̈ = Γ q̈ + Φ^lock f + ψ for the motion that joint torques τ_q and handle forces f produce
  // (no base actuation), with q̈ the joint part of that motion
  const int mrows = static_cast<int>(J.rows());
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(mrows, -3, 4);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(m->nv);
  tau.tail(m->nv - 6) = Eigen::VectorXd::LinSpaced(m->nv - 6, 1, -2);
  const Eigen::VectorXd generalized = tau + J.transpose() * f;
  const Eigen::VectorXd a = H.llt().solve(generalized - b);
  Eigen::VectorXd jdot_v(mrows);
  int row = 0;
  for (const Handle& h : handles) {
    const PointMotion p = point_jdot_v(*m, d, h.link, h.p_LinkPoint);
    if (h.with_orientation) {
      jdot_v.segment<3>(row) = p.angular;
      row += 3;
    }
    jdot_v.segment<3>(row) = p.linear;
    row += 3;
  }
  const Eigen::VectorXd rdd = J * a + jdot_v;
  const Eigen::VectorXd predicted =
      split.Gamma * a.tail(m->nv - 6) + split.Phi_lock * f + split.psi;
  EXPECT_LT((rdd - predicted).norm(), 1e-9 * (1 + rdd.norm()));
}

TEST(Osim, FloatingBaseSplitDoesNotAllocateOnceSized) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const auto handles = tree_handles(*m);
  const Eigen::VectorXd q = random_configuration(*m, 3);
  const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, 4));
  forward_kinematics(*m, d, q, v);
  compute_joint_jacobians(*m, d);
  const Eigen::VectorXd b = bias_forces(*m, d, q, v);
  crba(*m, d, q);
  FloatingBaseSplit split;
  floating_base_split(*m, d, handles, b, split);  // warm-up: sizes the split and its scratch
  const FloatingBaseSplit first = split;
  fixtures::AllocationCounter allocations;
  Eigen::internal::set_is_malloc_allowed(false);  // Eigen allocates with malloc, not new
  floating_base_split(*m, d, handles, b, split);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.count(), 0);
  // reusing the scratch changes nothing
  EXPECT_EQ(split.Gamma, first.Gamma);
  EXPECT_EQ(split.Phi_lock, first.Phi_lock);
  EXPECT_EQ(split.psi, first.psi);
}

}  // namespace
