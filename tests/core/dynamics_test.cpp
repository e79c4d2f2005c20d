// Tests for core/rnea.hpp, core/crba.hpp, core/aba.hpp: each algorithm against a second path.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "core/aba.hpp"
#include "core/branch_sparse_matrix.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "core/rnea.hpp"
#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;

struct RandomState {
  Eigen::VectorXd q, v, a, tau;
};

RandomState random_state(const Model& m, std::uint64_t seed) {
  RandomState s;
  s.q = random_configuration(m, seed);
  s.v = difference(m, s.q, random_configuration(m, seed + 7777));
  s.a = difference(m, s.q, random_configuration(m, seed + 8888)) * 3.0;
  s.tau = difference(m, s.q, random_configuration(m, seed + 9999)) * 10.0;
  return s;
}

std::vector<std::shared_ptr<const Model>> models() {
  return {fixtures::branching_tree(), fixtures::chain(7)};
}

// x = A⁻¹ b = L⁻¹ D⁻¹ L⁻ᵀ b with a factorized A
Eigen::VectorXd solve_factorized(const BranchSparseMatrix& A, const Eigen::VectorXd& b) {
  Eigen::VectorXd x = b;
  A.solve_lt(x);
  for (int k = 0; k < A.size(); ++k) x[k] /= A.diagonal(k);
  A.solve_l(x);
  return x;
}

TEST(Crba, MatchesRneaColumns) {
  for (const auto& m : models()) {
    Data d(*m);
    for (std::uint64_t seed = 0; seed < 5; ++seed) {
      const RandomState s = random_state(*m, seed);
      const Eigen::MatrixXd M = crba(*m, d, s.q);
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m->nv);
      const Eigen::VectorXd b = rnea(*m, d, s.q, zero, zero);
      for (int i = 0; i < m->nv; ++i) {
        const Eigen::VectorXd col = rnea(*m, d, s.q, zero, Eigen::VectorXd::Unit(m->nv, i)) - b;
        EXPECT_LT((M.col(i) - col).norm(), 1e-12 * (1 + col.norm())) << m->name << " col " << i;
      }
    }
  }
}

TEST(Crba, IsSymmetricPositiveDefinite) {
  for (const auto& m : models()) {
    Data d(*m);
    const Eigen::MatrixXd M = crba(*m, d, random_configuration(*m, 3));
    EXPECT_EQ(M, M.transpose());
    EXPECT_EQ(Eigen::LLT<Eigen::MatrixXd>(M).info(), Eigen::Success);
  }
}

// A free joint that is not the root (a body carried loose on an arm) with a subtree and a sibling
// after it: CRBA's six-column pass for a free joint starts at its own coordinates and stops at
// the end of its subtree, and H stays exactly symmetric. With a long chain below it (nv > 64)
// the mirror is the tiled copy.
std::shared_ptr<const Model> free_joint_on_an_arm(int chain_below) {
  ModelBuilder b("free_on_arm");
  LinkSpec arm = fixtures::box_link("arm", "", 2.0, Vector3(0.05, 0.05, 0.3));
  arm.joint.type = JointType::kRevolute;
  arm.joint.axis = Vector3::UnitY();
  arm.com = Vector3(0, 0, 0.2);
  b.add_link(arm);
  LinkSpec loose = fixtures::box_link("loose", "arm", 1.0, Vector3(0.1, 0.05, 0.05));
  loose.joint.type = JointType::kFree;
  loose.joint.X_PJ = {Eigen::AngleAxisd(0.4, Vector3(1, -1, 2).normalized()).toRotationMatrix(),
                      Vector3(0.05, 0, 0.4)};
  loose.com = Vector3(0.02, -0.01, 0.03);
  b.add_link(loose);
  std::string parent = "loose";
  for (int i = 0; i < chain_below; ++i) {
    LinkSpec l =
        fixtures::box_link("below" + std::to_string(i), parent, 0.3, Vector3(0.02, 0.02, 0.05));
    l.joint.type = JointType::kRevolute;
    l.joint.axis = Vector3::Unit(i % 3);
    l.joint.X_PJ.p = Vector3(0, 0.02, 0.1);
    l.com = Vector3(0, 0, 0.05);
    b.add_link(l);
    parent = l.name;
  }
  LinkSpec sibling = fixtures::box_link("sibling", "arm", 0.5, Vector3(0.05, 0.05, 0.05));
  sibling.joint.type = JointType::kSpherical;
  sibling.joint.X_PJ.p = Vector3(0, 0.1, 0.3);
  sibling.com = Vector3(0.01, 0.02, 0);
  b.add_link(sibling);
  return b.finalize();
}

TEST(Crba, AFreeJointBelowTheRootMatchesRneaColumnsAndIsSymmetric) {
  for (int chain_below : {2, 70}) {
    const auto m = free_joint_on_an_arm(chain_below);
    ASSERT_EQ(m->joint_type[2], JointType::kFree);
    ASSERT_EQ(m->nv > 64, chain_below > 60);
    Data d(*m);
    for (std::uint64_t seed = 0; seed < 3; ++seed) {
      const RandomState s = random_state(*m, seed);
      const Eigen::MatrixXd M = crba(*m, d, s.q);
      EXPECT_EQ(M, M.transpose()) << "nv " << m->nv;
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m->nv);
      const Eigen::VectorXd b = rnea(*m, d, s.q, zero, zero);
      for (int i = 0; i < m->nv; ++i) {
        const Eigen::VectorXd col = rnea(*m, d, s.q, zero, Eigen::VectorXd::Unit(m->nv, i)) - b;
        EXPECT_LT((M.col(i) - col).norm(), 1e-12 * (1 + col.norm()))
            << "nv " << m->nv << " col " << i;
      }
    }
  }
}

TEST(Rnea, InertiaTimesAccelerationPlusBias) {
  for (const auto& m : models()) {
    Data d(*m);
    const RandomState s = random_state(*m, 5);
    const Eigen::MatrixXd M = crba(*m, d, s.q);
    const Eigen::VectorXd b = bias_forces(*m, d, s.q, s.v);
    const Eigen::VectorXd tau = rnea(*m, d, s.q, s.v, s.a);
    EXPECT_LT((tau - (M * s.a + b)).norm(), 1e-11 * (1 + tau.norm()));
    // gravity alone
    const Eigen::VectorXd g = gravity_forces(*m, d, s.q);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m->nv);
    EXPECT_LT((g - rnea(*m, d, s.q, zero, zero)).norm(), 1e-13 * (1 + g.norm()));
  }
}

TEST(Rnea, ExternalForceMapsThroughTheTransposedJacobian) {
  // a world force F at a point adds −Jᵀ F to the torques needed for the same motion
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const RandomState s = random_state(*m, 9);
  const int link = m->link_index("hand");
  const Vector3 p_L(0.02, -0.03, 0.01);
  const Vector3 F_W(3, -2, 5);
  const Vector3 N_W(0.4, 0.1, -0.3);
  compute_joint_jacobians(*m, d, s.q);
  FrameJacobian J(m->nv);
  point_jacobian(*m, d, link, p_L, J);
  std::vector<Force> f_ext(m->njoints);
  f_ext[link] = link_force_from_world(d, link, F_W, d.X_W[link] * p_L, N_W);
  const Eigen::VectorXd tau0 = rnea(*m, d, s.q, s.v, s.a);
  const Eigen::VectorXd tau1 = rnea(*m, d, s.q, s.v, s.a, f_ext);
  const Eigen::VectorXd expected = tau0 - J.linear.transpose() * F_W - J.angular.transpose() * N_W;
  EXPECT_LT((tau1 - expected).norm(), 1e-11 * (1 + tau0.norm()));
}

TEST(Aba, InvertsRnea) {
  for (const auto& m : models()) {
    Data d(*m);
    for (std::uint64_t seed = 0; seed < 10; ++seed) {
      const RandomState s = random_state(*m, seed);
      std::vector<Force> f_ext(m->njoints);
      for (int i = 1; i < m->njoints; ++i)
        f_ext[i] = Force{Vector3(0.1 * i, -0.2, 0.3), Vector3(1, i * 0.5, -2)};
      const Eigen::VectorXd a = aba(*m, d, s.q, s.v, s.tau, f_ext);
      const Eigen::VectorXd tau = rnea(*m, d, s.q, s.v, a, f_ext);
      EXPECT_LT((tau - s.tau).norm(), 1e-10 * (1 + s.tau.norm())) << m->name << " seed " << seed;
    }
  }
}

TEST(Aba, EqualsInverseInertiaTimesTauMinusBias) {
  for (const auto& m : models()) {
    Data d(*m);
    const RandomState s = random_state(*m, 2);
    const Eigen::VectorXd b = bias_forces(*m, d, s.q, s.v);
    const Eigen::MatrixXd M = crba(*m, d, s.q);
    const Eigen::VectorXd expected = M.llt().solve(s.tau - b);
    const Eigen::VectorXd a = aba(*m, d, s.q, s.v, s.tau);
    EXPECT_LT((a - expected).norm(), 1e-10 * (1 + expected.norm()));
  }
}

TEST(Ltdl, HalfSolveOnAPathMatchesTheFullHalfSolve) {
  for (const auto& m : models()) {
    Data d(*m);
    const Eigen::VectorXd q = random_configuration(*m, 6);
    crba(*m, d, q);
    factorize_mass_matrix(*m, d);
    compute_joint_jacobians(*m, d, q);
    FrameJacobian J(m->nv);
    for (int link = 1; link < m->njoints; ++link) {
      point_jacobian(*m, d, link, Vector3(0.02, -0.01, 0.03), J);
      // Jᵀ's six columns are zero off the link's root path
      Eigen::MatrixXd X(m->nv, 6);
      X << J.angular.transpose(), J.linear.transpose();
      Eigen::MatrixXd expected = X;
      for (int c = 0; c < 6; ++c) solve_mass_matrix_lt(*m, d, expected.col(c));
      solve_mass_matrix_lt_on_path(*m, d, m->path_last_v(link), X);
      EXPECT_LT((X - expected).norm(), 1e-13 * (1 + expected.norm()))
          << m->name << " link " << link;
    }
  }
}

TEST(Ltdl, SparseSolveAgreesWithDenseCholesky) {
  for (const auto& m : models()) {
    Data d(*m);
    const Eigen::MatrixXd M = crba(*m, d, random_configuration(*m, 4));
    factorize_mass_matrix(*m, d);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m->nv, -2, 3);
    Eigen::VectorXd x = b;
    solve_mass_matrix(*m, d, x);
    EXPECT_LT((x - M.llt().solve(b)).norm(), 1e-10 * (1 + x.norm()));
    // reconstruct H = Lᵀ D L, and L is zero off the root paths
    Eigen::MatrixXd L = Eigen::MatrixXd::Identity(m->nv, m->nv);
    Eigen::VectorXd D(m->nv);
    for (int k = 0; k < m->nv; ++k) {
      D[k] = d.LTDL(k, k);
      for (int i = m->parent_v[k]; i >= 0; i = m->parent_v[i]) L(k, i) = d.LTDL(k, i);
    }
    EXPECT_LT((L.transpose() * D.asDiagonal() * L - M).norm(), 1e-12 * M.norm());
    Eigen::MatrixXd B = Eigen::MatrixXd::Identity(m->nv, m->nv);
    solve_mass_matrix_columns(*m, d, B);
    EXPECT_LT((M * B - Eigen::MatrixXd::Identity(m->nv, m->nv)).norm(), 1e-10);
  }
}

TEST(Ltdl, UpperOnlyFactorizationMatchesTheFullOneAndTouchesNothingElse) {
  for (const auto& m : models()) {
    Data d(*m);
    const Eigen::MatrixXd M = crba(*m, d, random_configuration(*m, 5));
    Eigen::MatrixXd full = M;
    ltdl_factorize(*m, full);
    // the upper ancestor positions of M on a matrix of sevens
    Eigen::MatrixXd upper = Eigen::MatrixXd::Constant(m->nv, m->nv, 7.0);
    int pattern = 0;
    for (int k = 0; k < m->nv; ++k) {
      for (int j = k; j >= 0; j = m->parent_v[j]) {
        upper(j, k) = M(j, k);
        ++pattern;
      }
    }
    ltdl_factorize_upper(*m, upper);
    int sevens = 0;
    for (int k = 0; k < m->nv; ++k) {
      for (int j = 0; j < m->nv; ++j) {
        bool on_pattern = false;
        for (int a = k; a >= 0 && !on_pattern; a = m->parent_v[a]) on_pattern = a == j;
        if (on_pattern) {
          EXPECT_NEAR(upper(j, k), full(j, k), 1e-12 * (1 + std::abs(full(j, k))))
              << m->name << " (" << j << ", " << k << ")";
        } else {
          sevens += upper(j, k) == 7.0;
        }
      }
    }
    EXPECT_EQ(sevens, m->nv * m->nv - pattern) << m->name << ": an entry off the pattern changed";
    // the solves read the upper factor alone
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m->nv, -2, 3);
    Eigen::VectorXd x = b;
    ltdl_solve(*m, upper, x);
    EXPECT_LT((x - M.llt().solve(b)).norm(), 1e-10 * (1 + x.norm())) << m->name;
  }
}

TEST(BranchSparseMatrix, FactorizationAndSolvesMatchTheDenseOnes) {
  auto models_with_a_figure = models();
  models_with_a_figure.push_back(fixtures::human48());  // free root, ball joints: deep paths
  // factorize() eliminates chains in blocks of up to three columns: 5 hinges make one of three
  // and one of two, 7 (in models()) two of three and one of one
  models_with_a_figure.push_back(fixtures::chain(5));
  for (const auto& m : models_with_a_figure) {
    Data d(*m);
    const Eigen::MatrixXd M = crba(*m, d, random_configuration(*m, 11));
    BranchSparseMatrix A(*m);
    ASSERT_EQ(A.size(), m->nv);
    // each column holds k's root path, root first, k last
    for (int k = 0; k < m->nv; ++k) {
      EXPECT_EQ(A.path(k)[A.depth(k)], k) << m->name;
      for (int p = A.depth(k); p > 0; --p) {
        EXPECT_EQ(A.path(k)[p - 1], m->parent_v[A.path(k)[p]]) << m->name << " column " << k;
      }
      EXPECT_EQ(m->parent_v[A.path(k)[0]], -1) << m->name << " column " << k;
      for (int p = 0; p <= A.depth(k); ++p) A.column(k)[p] = M(A.path(k)[p], k);
    }
    // M has the tree's sparsity, so the pattern holds all of it
    EXPECT_EQ((A.dense() - M).norm(), 0.0) << m->name;
    Eigen::MatrixXd full = M;
    ltdl_factorize(*m, full);
    A.factorize();
    for (int k = 0; k < m->nv; ++k) {
      for (int p = 0; p <= A.depth(k); ++p) {
        const double expected = full(A.path(k)[p], k);
        EXPECT_NEAR(A.column(k)[p], expected, 1e-12 * (1 + std::abs(expected)))
            << m->name << " (" << A.path(k)[p] << ", " << k << ")";
      }
    }
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m->nv, -2, 3);
    const Eigen::VectorXd x = solve_factorized(A, b);
    EXPECT_LT((x - M.llt().solve(b)).norm(), 1e-10 * (1 + x.norm())) << m->name;
    // every column at once, as one column at a time: a dense one, a zero one, one on a leaf's path
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> X =
        Eigen::MatrixXd::Zero(m->nv, 3);
    X.col(0) = b;
    X(m->nv - 1, 2) = 1.5;
    const Eigen::MatrixXd before = X;
    A.solve_lt_columns(X);
    for (int c = 0; c < 3; ++c) {
      Eigen::VectorXd column = before.col(c);
      A.solve_lt(column);
      EXPECT_EQ((X.col(c) - column).norm(), 0.0) << m->name << " column " << c;
    }
    EXPECT_EQ(X.col(1).norm(), 0.0) << m->name;
  }
}

TEST(BranchSparseMatrix, PathGramAddsTheNormalMatrixOfRowsOnOnePath) {
  // A += PᵀP for rows on a leaf's root path, as the dense PᵀP of the rows spread over all columns;
  // 6 and 3 rows (the unrolled counts) and 4 (the general loop)
  auto models_with_a_figure = models();
  models_with_a_figure.push_back(fixtures::human48());
  for (const auto& m : models_with_a_figure) {
    BranchSparseMatrix A(*m);
    Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(m->nv, m->nv);
    for (const int rows : {6, 3, 4}) {
      for (int leaf = 0; leaf < m->nv; leaf += 5) {
        const int n = A.depth(leaf) + 1;
        const BranchSparseMatrix::RowMajorMatrix P =
            Eigen::MatrixXd::Random(rows, n) + Eigen::MatrixXd::Constant(rows, n, leaf);
        Eigen::MatrixXd spread = Eigen::MatrixXd::Zero(rows, m->nv);
        for (int a = 0; a < n; ++a) spread.col(A.path(leaf)[a]) = P.col(a);
        expected += spread.transpose() * spread;
        A.add_path_gram(leaf, P);
      }
    }
    EXPECT_LT((A.dense() - expected).norm(), 1e-12 * expected.norm()) << m->name;
  }
}

TEST(BranchSparseMatrix, ColumnsNoRowTouchesAreSkippedAndTheSolvesStayExact) {
  // A normal matrix of rows on a few paths plus a ridge: coordinates off every path have only
  // their diagonal, take no part in the elimination and are skipped by the solves. Leaves in the
  // middle of a chain leave a chain block half coupled (its root end on the path, its leaf end
  // off it).
  std::vector<std::pair<std::shared_ptr<const Model>, std::vector<int>>> cases = {
      {fixtures::chain(7), {2}},
      {fixtures::chain(5), {0}},
      {fixtures::branching_tree(), {1}},
  };
  const auto human = fixtures::human48();
  cases.push_back(
      {human,
       {human->idx_v[human->link_index("l_foot")], human->idx_v[human->link_index("head")]}});
  for (const auto& [m, leaves] : cases) {
    BranchSparseMatrix A(*m);
    Eigen::MatrixXd dense = Eigen::MatrixXd::Identity(m->nv, m->nv) * 0.5;
    std::vector<char> on_a_path(m->nv, 0);
    for (const int leaf : leaves) {
      const int n = A.depth(leaf) + 1;
      const BranchSparseMatrix::RowMajorMatrix P = Eigen::MatrixXd::Random(6, n);
      Eigen::MatrixXd spread = Eigen::MatrixXd::Zero(6, m->nv);
      for (int a = 0; a < n; ++a) {
        spread.col(A.path(leaf)[a]) = P.col(a);
        on_a_path[A.path(leaf)[a]] = 1;
      }
      dense += spread.transpose() * spread;
      A.add_path_gram(leaf, P);
    }
    for (int c = 0; c < m->nv; ++c) A.diagonal(c) += 0.5;
    A.factorize();
    int skipped = 0;
    for (int k = 0; k < m->nv; ++k) {
      // a coordinate is coupled when it is on a path and has an ancestor
      EXPECT_EQ(A.coupled(k), on_a_path[k] && A.depth(k) > 0) << m->name << " column " << k;
      skipped += !A.coupled(k);
    }
    EXPECT_GT(skipped, 0) << m->name;
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m->nv, -2, 3);
    const Eigen::VectorXd solved = solve_factorized(A, b);
    EXPECT_LT((solved - dense.llt().solve(b)).norm(), 1e-12 * (1 + solved.norm())) << m->name;
    BranchSparseMatrix::RowMajorMatrix X = Eigen::MatrixXd::Zero(m->nv, 2);
    X.col(0) = b;
    X(m->nv - 1, 1) = 1.5;
    const Eigen::MatrixXd before = X;
    Eigen::VectorXd x = before.col(0);
    A.solve_lt(x);
    A.solve_lt_columns(X);
    EXPECT_EQ((X.col(0) - x).norm(), 0.0) << m->name;
    // L⁻ᵀ of the dense factor: Lᵀ D L = A with L unit lower triangular, column by column
    const Eigen::MatrixXd L_dense = [&, nv = m->nv] {
      Eigen::MatrixXd L = Eigen::MatrixXd::Identity(nv, nv);
      for (int k = 0; k < nv; ++k) {
        for (int p = 0; p < A.depth(k); ++p) L(k, A.path(k)[p]) = A.column(k)[p];
      }
      return L;
    }();
    Eigen::VectorXd D(m->nv);
    for (int k = 0; k < m->nv; ++k) D[k] = A.diagonal(k);
    EXPECT_LT((L_dense.transpose() * D.asDiagonal() * L_dense - dense).norm(), 1e-12 * dense.norm())
        << m->name;
    EXPECT_LT((L_dense.transpose() * X.col(1) - before.col(1)).norm(), 1e-12) << m->name;
  }
}

TEST(BranchSparseMatrix, FactorizesAndSolvesWithoutAllocating) {
  const auto m = fixtures::human48();
  Data d(*m);
  const Eigen::MatrixXd M = crba(*m, d, random_configuration(*m, 3));
  BranchSparseMatrix A(*m), copy(*m);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(m->nv);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> X =
      Eigen::MatrixXd::Ones(m->nv, 4);
  fixtures::AllocationCounter allocations;
  Eigen::internal::set_is_malloc_allowed(false);
  A.set_zero();
  for (int k = 0; k < m->nv; ++k) {
    for (int p = 0; p <= A.depth(k); ++p) A.column(k)[p] = M(A.path(k)[p], k);
  }
  copy = A;
  copy.factorize();
  copy.solve_lt(x);
  copy.solve_l(x);
  copy.solve_lt_columns(X);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.count(), 0);
}

TEST(Dynamics, PerStepPathDoesNotAllocate) {
  const auto m = fixtures::branching_tree();
  Data d(*m);
  const RandomState s = random_state(*m, 1);
  Eigen::VectorXd x = s.tau;
  fixtures::AllocationCounter allocations;
  Eigen::internal::set_is_malloc_allowed(false);
  rnea(*m, d, s.q, s.v, s.a);
  crba(*m, d, s.q);
  factorize_mass_matrix(*m, d);
  solve_mass_matrix(*m, d, x);
  aba(*m, d, s.q, s.v, s.tau);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.count(), 0);
}

TEST(Dynamics, LongChainsStayAccurate) {
  // hard case #19: 512 links, forward then inverse dynamics reproduces the torques
  const auto m = fixtures::chain(512);
  Data d(*m);
  const RandomState s = random_state(*m, 12);
  const Eigen::VectorXd a = aba(*m, d, s.q, s.v, s.tau);
  const Eigen::VectorXd tau = rnea(*m, d, s.q, s.v, a);
  EXPECT_LT((tau - s.tau).norm() / s.tau.norm(), 1e-8);
  // the same through CRBA and the sparse factorization
  crba(*m, d, s.q);
  factorize_mass_matrix(*m, d);
  Eigen::VectorXd a2 = s.tau - bias_forces(*m, d, s.q, s.v);
  solve_mass_matrix(*m, d, a2);
  EXPECT_LT((rnea(*m, d, s.q, s.v, a2) - s.tau).norm() / s.tau.norm(), 1e-8);
}

}  // namespace
