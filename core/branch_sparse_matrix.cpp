#include "core/branch_sparse_matrix.hpp"

#include <algorithm>

namespace core {

namespace {

// y[0 … n) −= a x[0 … n) for two distinct columns (__restrict__: no overlap check before the loop,
// which costs more than these short updates)
inline void subtract_scaled_prefix(double* __restrict__ y,
                                   const double* __restrict__ x,
                                   double a,
                                   int n) {
  for (int j = 0; j < n; ++j) y[j] -= a * x[j];
}

}  // namespace

BranchSparseMatrix::BranchSparseMatrix(const Model& model) : offset_(model.nv), depth_(model.nv) {
  int total = 0;
  for (int k = 0; k < model.nv; ++k) {
    // parent_v[k] < k: a coordinate's ancestors come before it
    depth_[k] = model.parent_v[k] < 0 ? 0 : depth_[model.parent_v[k]] + 1;
    offset_[k] = total;
    total += depth_[k] + 1;
  }
  path_.resize(total);
  values_.assign(total, 0.0);
  for (int k = 0; k < model.nv; ++k) {
    for (int j = k; j >= 0; j = model.parent_v[j]) path_[offset_[k] + depth_[j]] = j;
  }
}

void BranchSparseMatrix::set_zero() { std::fill(values_.begin(), values_.end(), 0.0); }

void BranchSparseMatrix::factorize() {
  // eliminate from the leaves up: for each ancestor i of k (at depth p), A(j, i) −= a A(j, k) for i
  // and its ancestors j (the prefix 0 … p of both columns), then L(k, i) = a = A(i, k) / A(k, k)
  for (int k = size() - 1; k >= 0; --k) {
    double* const Ak = column(k);
    const int* const path_k = path(k);
    const double inv_dk = 1.0 / Ak[depth_[k]];
    for (int p = depth_[k] - 1; p >= 0; --p) {
      const double a = Ak[p] * inv_dk;
      double* const Ai = column(path_k[p]);
      subtract_scaled_prefix(Ai, Ak, a, p + 1);
      Ak[p] = a;
    }
  }
}

void BranchSparseMatrix::solve_lt(Eigen::Ref<Eigen::VectorXd> x) const {
  // back substitution with Lᵀ: x_j −= L(k, j) x_k for the ancestors j of each k, leaves first
  double* const xs = x.data();
  for (int k = size() - 1; k >= 0; --k) {
    const double xk = xs[k];
    if (xk == 0) continue;  // a zero entry changes nothing: sparse right-hand sides cost little
    const double* const Lk = column(k);
    const int* const path_k = path(k);
    for (int p = 0; p < depth_[k]; ++p) xs[path_k[p]] -= xk * Lk[p];
  }
}

void BranchSparseMatrix::solve_lt_columns(
    Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> X) const {
  // solve_lt on every column, a row of X at a time (short rows: plain loops)
  const Eigen::Index n = X.cols(), stride = X.outerStride();
  for (int k = size() - 1; k >= 0; --k) {
    const double* const Xk = X.data() + k * stride;
    if (std::all_of(Xk, Xk + n, [](double x) { return x == 0; })) continue;
    const double* const Lk = column(k);
    const int* const path_k = path(k);
    for (int p = 0; p < depth_[k]; ++p) {
      double* const Xj = X.data() + path_k[p] * stride;
      for (Eigen::Index c = 0; c < n; ++c) Xj[c] -= Lk[p] * Xk[c];
    }
  }
}

void BranchSparseMatrix::solve_l(Eigen::Ref<Eigen::VectorXd> x) const {
  // forward substitution with L: x_k −= Σ L(k, j) x_j over the ancestors j, root first
  double* const xs = x.data();
  for (int k = 0; k < size(); ++k) {
    const double* const Lk = column(k);
    const int* const path_k = path(k);
    double sum = 0;
    for (int p = 0; p < depth_[k]; ++p) sum += Lk[p] * xs[path_k[p]];
    xs[k] -= sum;
  }
}

Eigen::MatrixXd BranchSparseMatrix::dense() const {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(size(), size());
  for (int k = 0; k < size(); ++k) {
    for (int p = 0; p <= depth_[k]; ++p) {
      A(path(k)[p], k) = column(k)[p];
      A(k, path(k)[p]) = column(k)[p];
    }
  }
  return A;
}

}  // namespace core
