// Cholesky factorization and solves for the solver's small dense systems (a few to a few dozen
// rows), written as plain loops: at these sizes they beat the blocked general-purpose kernels.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace ik {

/// The lower triangle of G = J Jᵀ (G square, J with as many rows), summed a column of J at a time:
/// each is a short contiguous vector, and the zero columns (coordinates off a task's path) are
/// skipped. The rest of G is left as it was.
inline void gram_lower(const Eigen::Ref<const Eigen::MatrixXd>& J, Eigen::Ref<Eigen::MatrixXd> G) {
  const Eigen::Index m = J.rows();
  for (Eigen::Index j = 0; j < m; ++j) G.col(j).tail(m - j).setZero();
  for (Eigen::Index c = 0; c < J.cols(); ++c) {
    const double* const Jc = J.col(c).data();
    for (Eigen::Index j = 0; j < m; ++j) {
      const double a = Jc[j];
      if (a == 0) continue;
      double* const Gj = G.col(j).data();
      for (Eigen::Index i = j; i < m; ++i) Gj[i] += a * Jc[i];
    }
  }
}

/// A = L Lᵀ in place on the lower triangle of the square block A. Returns false when A is not
/// positive definite (a pivot <= 0 or not finite).
inline bool cholesky_in_place(Eigen::Ref<Eigen::MatrixXd> A) {
  const Eigen::Index m = A.rows();
  for (Eigen::Index j = 0; j < m; ++j) {
    double d = A(j, j);
    for (Eigen::Index k = 0; k < j; ++k) d -= A(j, k) * A(j, k);
    if (!(d > 0) || !std::isfinite(d)) return false;
    d = std::sqrt(d);
    A(j, j) = d;
    const double inv = 1.0 / d;
    for (Eigen::Index i = j + 1; i < m; ++i) {
      double s = A(i, j);
      for (Eigen::Index k = 0; k < j; ++k) s -= A(i, k) * A(j, k);
      A(i, j) = s * inv;
    }
  }
  return true;
}

/// B ← L⁻¹ B (forward substitution with the factor's lower triangle).
inline void forward_substitute(const Eigen::Ref<const Eigen::MatrixXd>& L,
                               Eigen::Ref<Eigen::MatrixXd> B) {
  // row by row, every column at once: one division per row instead of one per entry (a division
  // takes as long as a dozen multiply-adds)
  const Eigen::Index m = L.rows();
  for (Eigen::Index i = 0; i < m; ++i) {
    const double inv = 1.0 / L(i, i);
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      double s = B(i, c);
      for (Eigen::Index k = 0; k < i; ++k) s -= L(i, k) * B(k, c);
      B(i, c) = s * inv;
    }
  }
}

/// B ← (L Lᵀ)⁻¹ B.
inline void cholesky_solve(const Eigen::Ref<const Eigen::MatrixXd>& L,
                           Eigen::Ref<Eigen::MatrixXd> B) {
  forward_substitute(L, B);
  const Eigen::Index m = L.rows();
  for (Eigen::Index i = m - 1; i >= 0; --i) {
    const double inv = 1.0 / L(i, i);
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      double s = B(i, c);
      for (Eigen::Index k = i + 1; k < m; ++k) s -= L(k, i) * B(k, c);
      B(i, c) = s * inv;
    }
  }
}

}  // namespace ik
