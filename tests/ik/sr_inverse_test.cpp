// Tests for ik/sr_inverse.hpp (digest §7 test 1).
#include "ik/sr_inverse.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>

#include "tests/fixtures/allocation_counter.hpp"

namespace {

using ik::DampingSchedule;
using ik::SrInverse;

Eigen::MatrixXd random_matrix(int m, int n, int seed) {
  srand(seed);
  return Eigen::MatrixXd::Random(m, n);
}

TEST(SrInverse, ApproachesThePseudoinverseAsDampingVanishes) {
  for (auto [m, n] : {std::pair{3, 7}, std::pair{7, 3}, std::pair{5, 5}}) {
    const Eigen::MatrixXd A = random_matrix(m, n, m * 10 + n);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m, -1, 2);
    const Eigen::VectorXd expected = A.completeOrthogonalDecomposition().solve(b);
    SrInverse sr;
    Eigen::VectorXd x(n);
    sr.solve(A, b, 1e-12, DampingSchedule::kConstant, 1.0, x);
    EXPECT_LT((x - expected).norm(), 1e-8 * (1 + expected.norm())) << m << "x" << n;
  }
}

TEST(SrInverse, BothFormsMinimizeTheDampedObjective) {
  // x = argmin |b − Ax|² + k|x|²  ⇔  (AᵀA + kE) x = Aᵀ b
  for (auto [m, n] : {std::pair{4, 9}, std::pair{9, 4}}) {
    const Eigen::MatrixXd A = random_matrix(m, n, 3 + m);
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m, 2, -1);
    const double k = 0.05;
    SrInverse sr;
    Eigen::VectorXd x(n);
    sr.solve(A, b, k, DampingSchedule::kConstant, 1.0, x);
    const Eigen::VectorXd residual =
        (A.transpose() * A + k * Eigen::MatrixXd::Identity(n, n)) * x - A.transpose() * b;
    EXPECT_LT(residual.norm(), 1e-12);
  }
}

TEST(SrInverse, GainIsBoundedAtAnExactSingularity) {
  // rank-1 matrix: |A* b| <= |b| / (2√k) for every b
  Eigen::MatrixXd A(3, 4);
  A << 1, 2, 3, 4, 2, 4, 6, 8, -1, -2, -3, -4;
  const double k = 1e-4;
  SrInverse sr;
  Eigen::VectorXd x(4);
  for (int t = 0; t < 20; ++t) {
    srand(t);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(3);
    sr.solve(A, b, k, DampingSchedule::kConstant, 1.0, x);
    EXPECT_TRUE(x.allFinite());
    EXPECT_LE(x.norm(), b.norm() / (2 * std::sqrt(k)) * (1 + 1e-12));
  }
  // near-singular with tiny damping stays finite too
  A(2, 3) += 1e-14;
  sr.solve(A, Eigen::Vector3d(1, 0, 0), 1e-10, DampingSchedule::kConstant, 1.0, x);
  EXPECT_TRUE(x.allFinite());
}

TEST(SrInverse, ManipulabilityScheduleDampsOnlyNearSingularities) {
  SrInverse sr;
  Eigen::VectorXd x(3);
  const Eigen::MatrixXd well = Eigen::MatrixXd::Identity(2, 3);
  auto r = sr.solve(well, Eigen::Vector2d(1, 1), 0.1, DampingSchedule::kManipulability, 0.5, x);
  EXPECT_LT(r.damping, 1e-11);  // w = 1 > w0: no damping beyond the floor
  EXPECT_NEAR(r.manipulability, 1.0, 1e-9);
  Eigen::MatrixXd near(2, 3);
  near << 1, 0, 0, 1, 1e-4, 0;
  r = sr.solve(near, Eigen::Vector2d(1, 0), 0.1, DampingSchedule::kManipulability, 0.5, x);
  EXPECT_GT(r.damping, 0.05);
  EXPECT_TRUE(x.allFinite());
}

TEST(SrInverse, DoesNotAllocateOnceSized) {
  SrInverse sr;
  const Eigen::MatrixXd A = random_matrix(30, 20, 1);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(30);
  Eigen::VectorXd x(20);
  sr.solve(A, b, 1e-3, DampingSchedule::kConstant, 1.0, x);
  fixtures::AllocationCounter allocations;
  sr.solve(A.topRows(25), b.head(25), 1e-3, DampingSchedule::kConstant, 1.0, x);  // smaller: reuses
  sr.solve(A.topRows(10), b.head(10), 1e-3, DampingSchedule::kManipulability, 0.1, x);
  EXPECT_EQ(allocations.count(), 0);
}

}  // namespace
