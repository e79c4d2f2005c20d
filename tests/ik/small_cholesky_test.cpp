// The solver's small dense kernels (ik/small_cholesky.hpp) against Eigen's general ones.
#include "ik/small_cholesky.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

namespace {

// m rows over 20 columns, every third column zero (a coordinate off the task's path) and one
// column zero except for one row (a zero entry inside a nonzero column)
Eigen::MatrixXd task_like_rows(int m) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Random(m, 20);
  for (int c = 0; c < J.cols(); c += 3) J.col(c).setZero();
  J.col(4).setZero();
  J(m - 1, 4) = 0.5;
  return J;
}

TEST(SmallCholesky, GramLowerIsTheLowerTriangleOfJJtForEveryRowCount) {
  // 6 and 3 rows take their own kernels, the others the general loop
  for (int m = 1; m <= 7; ++m) {
    const Eigen::MatrixXd J = task_like_rows(m);
    const Eigen::MatrixXd expected = J * J.transpose();
    constexpr double kUntouched = 42;
    Eigen::MatrixXd G = Eigen::MatrixXd::Constant(m, m, kUntouched);
    ik::gram_lower(J, G);
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        if (i >= j) {
          EXPECT_NEAR(G(i, j), expected(i, j), 1e-14)
              << "m = " << m << ", (" << i << ", " << j << ")";
        } else {
          EXPECT_EQ(G(i, j), kUntouched) << "m = " << m << ": the upper triangle is left as it was";
        }
      }
    }
  }
}

TEST(SmallCholesky, GramLowerOfZeroRowsIsZero) {
  for (int m : {3, 5, 6}) {
    Eigen::MatrixXd G = Eigen::MatrixXd::Constant(m, m, 7.0);
    ik::gram_lower(Eigen::MatrixXd::Zero(m, 10), G);
    EXPECT_TRUE(G.triangularView<Eigen::Lower>().toDenseMatrix().isZero()) << "m = " << m;
  }
}

TEST(SmallCholesky, FactorizationAndSolveMatchEigen) {
  const Eigen::MatrixXd J = task_like_rows(6);
  Eigen::MatrixXd G(6, 6);
  ik::gram_lower(J, G);
  G.diagonal().array() += 1e-3;
  const Eigen::MatrixXd A = G.selfadjointView<Eigen::Lower>();
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(6, -1, 1), x = b;
  ASSERT_TRUE(ik::cholesky_in_place(G));
  ik::cholesky_solve(G, x);
  EXPECT_LT((x - A.llt().solve(b)).norm(), 1e-9 * x.norm());
  Eigen::MatrixXd indefinite = -Eigen::MatrixXd::Identity(3, 3);
  EXPECT_FALSE(ik::cholesky_in_place(indefinite));
}

}  // namespace
