// Cholesky factorization and solves for the solver's small dense systems (a few to a few dozen
// rows), written as plain loops: at these sizes they beat the blocked general-purpose kernels.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace ik {

namespace detail {
// gram_lower for exactly M rows: the M(M+1)/2 sums stay in registers across the columns, and a
// column is skipped after one test of its M entries
template <int M>
inline void gram_lower_fixed(const Eigen::Ref<const Eigen::MatrixXd>& J,
                             Eigen::Ref<Eigen::MatrixXd> G) {
  double sum[M][M] = {};  // sum[j][i] = G(i, j) for i >= j
  for (Eigen::Index c = 0; c < J.cols(); ++c) {
    const double* const Jc = J.col(c).data();
    double x[M];
    bool zero = true;
    for (int i = 0; i < M; ++i) x[i] = Jc[i], zero = zero && Jc[i] == 0;
    if (zero) continue;
    for (int j = 0; j < M; ++j) {
      for (int i = j; i < M; ++i) sum[j][i] += x[j] * x[i];
    }
  }
  for (int j = 0; j < M; ++j) {
    for (int i = j; i < M; ++i) G(i, j) = sum[j][i];
  }
}
}  // namespace detail

/// The lower triangle of G = J Jᵀ (G square, J with as many rows), summed a column of J at a time:
/// each is a short contiguous vector, and the zero columns (coordinates off a task's path) are
/// skipped. The rest of G is left as it was. Six rows (a 6-D drag) and three have their own
/// kernel.
inline void gram_lower(const Eigen::Ref<const Eigen::MatrixXd>& J, Eigen::Ref<Eigen::MatrixXd> G) {
  const Eigen::Index m = J.rows();
  if (m == 6) return detail::gram_lower_fixed<6>(J, G);
  if (m == 3) return detail::gram_lower_fixed<3>(J, G);
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
