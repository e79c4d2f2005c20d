#include "core/branch_sparse_matrix.hpp"

#include <algorithm>
#include <cassert>

#include "core/scaled_sum.hpp"

namespace core {

namespace {

// y[0 … n) −= a0 x0 + a1 x1 + a2 x2 over the same prefix of two or three columns (x2 null: two)
inline void subtract_combination_prefix(double* __restrict__ y,
                                        const double* __restrict__ x0,
                                        const double* __restrict__ x1,
                                        const double* __restrict__ x2,
                                        double a0,
                                        double a1,
                                        double a2,
                                        int n) {
  if (x2 == nullptr) {
    for (int j = 0; j < n; ++j) y[j] -= a0 * x0[j] + a1 * x1[j];
    return;
  }
  for (int j = 0; j < n; ++j) y[j] -= a0 * x0[j] + a1 * x1[j] + a2 * x2[j];
}

// y[0 … n) += Σ_t x_t[a] x_t[0 … n), x_t = x + t × stride: M rows of P scaled by their entries
// in column a, all at once, so each entry of y is loaded and stored once instead of once per row
template <int M>
inline void add_scaled_rows_prefix(
    double* __restrict__ y, const double* __restrict__ x, Eigen::Index stride, int a, int n) {
  double s[M];
  for (int t = 0; t < M; ++t) s[t] = x[t * stride + a];
  for (int j = 0; j < n; ++j) {
    double sum = 0;
    for (int t = 0; t < M; ++t) sum += s[t] * x[t * stride + j];
    y[j] += sum;
  }
}

}  // namespace

BranchSparseMatrix::BranchSparseMatrix(const Model& model)
    : offset_(model.nv),
      depth_(model.nv),
      parent_(model.parent_v),
      chain_start_(model.chain_start_v) {
  int total = 0;
  for (int k = 0; k < model.nv; ++k) {
    // parent_v[k] < k: a coordinate's ancestors come before it
    depth_[k] = model.parent_v[k] < 0 ? 0 : depth_[model.parent_v[k]] + 1;
    offset_[k] = total;
    total += depth_[k] + 1;
  }
  path_.resize(total);
  values_.assign(total, 0.0);
  coupled_.assign(model.nv, 1);
  for (int k = 0; k < model.nv; ++k) {
    for (int j = k; j >= 0; j = model.parent_v[j]) path_[offset_[k] + depth_[j]] = j;
  }
  // chain blocks for factorize(), leaves first: runs lo … hi of at most kMaxChainBlock coordinates
  // in which each of lo … hi − 1 has one child, the next (a ball or free joint's coordinates, a
  // run of hinges)
  std::vector<int> children(model.nv, 0);
  for (int k = 0; k < model.nv; ++k) {
    if (model.parent_v[k] >= 0) ++children[model.parent_v[k]];
  }
  for (int hi = model.nv - 1; hi >= 0;) {
    int lo = hi;
    while (hi - lo + 1 < kMaxChainBlock && lo > 0 && model.parent_v[lo] == lo - 1 &&
           children[lo - 1] == 1) {
      --lo;
    }
    chain_blocks_.emplace_back(lo, hi);
    hi = lo - 1;
  }
}

void BranchSparseMatrix::set_zero() { std::fill(values_.begin(), values_.end(), 0.0); }

void BranchSparseMatrix::add_path_gram(int leaf, const Eigen::Ref<const RowMajorMatrix>& P) {
  // A(path[c], path[a]) += P(:, c) · P(:, a) for c <= a. Column path[a] sits at depth a, so its
  // entries 0 … a are the pairs (c, a): it gains Σ_t P(t, a) P(t, 0 … a), scaled prefixes of the
  // (contiguous) rows of P. A link task has 6 or 3 rows: those counts are unrolled.
  assert(P.cols() == depth(leaf) + 1);
  const int* const p = path(leaf);
  const Eigen::Index m = P.rows(), stride = P.outerStride();
  for (int a = 0; a < static_cast<int>(P.cols()); ++a) {
    double* const Aa = column(p[a]);
    if (m == 6) {
      add_scaled_rows_prefix<6>(Aa, P.data(), stride, a, a + 1);
    } else if (m == 3) {
      add_scaled_rows_prefix<3>(Aa, P.data(), stride, a, a + 1);
    } else {
      for (Eigen::Index t = 0; t < m; ++t) add_scaled(Aa, P.row(t).data(), P(t, a), a + 1);
    }
  }
}

void BranchSparseMatrix::factorize() {
  // Eliminate from the leaves up (RBDA Table 6.3): for each ancestor i of k (at depth p),
  // A(j, i) −= a A(j, k) for i and its ancestors j (the prefix 0 … p of both columns), then
  // L(k, i) = a = A(i, k) / A(k, k). A chain block lo … hi first eliminates inside itself; its
  // columns are then final and share their ancestors, so each ancestor column is updated by all of
  // them in one pass: one sweep over the target instead of one per column of the block. A column
  // with no entry above its diagonal has a = 0 for every ancestor: it takes no part.
  for (const auto& [lo, hi] : chain_blocks_) {
    const int top = depth_[lo];        // ancestors of the block sit at depths 0 … top − 1
    double inv_pivot[kMaxChainBlock];  // 1 / A(k, k) for k = lo … hi
    for (int k = hi; k >= lo; --k) {
      double* const Ak = column(k);
      const int dk = depth_[k];
      coupled_[k] = std::any_of(Ak, Ak + dk, [](double x) { return x != 0; });
      if (!coupled_[k]) continue;
      const double inv_dk = inv_pivot[k - lo] = 1.0 / Ak[dk];
      for (int p = dk - 1; p >= top; --p) {  // the block's own columns, lo + p − top
        const double a = Ak[p] * inv_dk;
        add_scaled(column(lo + p - top), Ak, -a, p + 1);
        Ak[p] = a;
      }
    }
    // the block's coupled columns, root end first (the order of the sums below)
    double* columns[kMaxChainBlock];
    double inv_d[kMaxChainBlock];
    int coupled_columns = 0;
    for (int k = lo; k <= hi; ++k) {
      if (!coupled_[k]) continue;
      columns[coupled_columns] = column(k);
      inv_d[coupled_columns] = inv_pivot[k - lo];
      ++coupled_columns;
    }
    if (coupled_columns == 0) continue;
    const int* const path_lo = path(lo);
    for (int p = top - 1; p >= 0; --p) {
      double* const Ai = column(path_lo[p]);
      double a[kMaxChainBlock];
      for (int b = 0; b < coupled_columns; ++b) a[b] = columns[b][p] * inv_d[b];
      switch (coupled_columns) {
        case 1:
          add_scaled(Ai, columns[0], -a[0], p + 1);
          break;
        case 2:
          subtract_combination_prefix(Ai, columns[0], columns[1], nullptr, a[0], a[1], 0.0, p + 1);
          break;
        default:
          subtract_combination_prefix(Ai, columns[0], columns[1], columns[2], a[0], a[1], a[2],
                                      p + 1);
      }
      for (int b = 0; b < coupled_columns; ++b) columns[b][p] = a[b];
    }
  }
}

void BranchSparseMatrix::solve_lt(Eigen::Ref<Eigen::VectorXd> x) const {
  // back substitution with Lᵀ: x_j −= L(k, j) x_k for the ancestors j of each k, leaves first. A
  // run of ancestors c … c + n − 1 sits at depths depth(c) … depth(c) + n − 1 of k's column, so
  // each run is one contiguous update.
  double* const xs = x.data();
  for (int k = size() - 1; k >= 0; --k) {
    const double xk = xs[k];
    // a zero entry or an uncoupled column changes nothing: sparse right-hand sides cost little
    if (xk == 0 || !coupled_[k]) continue;
    const double* const Lk = column(k);
    for_each_ancestor_run(chain_start_.data(), parent_.data(), parent_[k],
                          [&](int c, int n) { add_scaled(xs + c, Lk + depth_[c], -xk, n); });
  }
}

void BranchSparseMatrix::solve_lt_columns(Eigen::Ref<RowMajorMatrix> X) const {
  // solve_lt on every column, a row of X at a time (short rows: plain loops)
  const Eigen::Index n = X.cols(), stride = X.outerStride();
  for (int k = size() - 1; k >= 0; --k) {
    if (!coupled_[k]) continue;
    const double* const Xk = X.data() + k * stride;
    if (std::all_of(Xk, Xk + n, [](double x) { return x == 0; })) continue;
    const double* const Lk = column(k);
    const int* const path_k = path(k);
    for (int p = 0; p < depth_[k]; ++p) {
      double* const Xj = X.data() + path_k[p] * stride;
      add_scaled(Xj, Xk, -Lk[p], static_cast<int>(n));  // distinct rows: p < depth(k)
    }
  }
}

void BranchSparseMatrix::solve_l(Eigen::Ref<Eigen::VectorXd> x) const {
  // forward substitution with L: x_k −= Σ L(k, j) x_j over the ancestors j, root first. Through
  // the path's indices, not by runs as in solve_lt: one sum over the whole path costs less than a
  // short sum per run.
  double* const xs = x.data();
  for (int k = 0; k < size(); ++k) {
    if (!coupled_[k]) continue;
    const double* const Lk = column(k);
    const int* const path_k = path(k);
    // two partial sums: each add waits on the one before it, so one sum is a chain as long as
    // the path
    double even = 0, odd = 0;
    int p = 0;
    for (; p + 1 < depth_[k]; p += 2) {
      even += Lk[p] * xs[path_k[p]];
      odd += Lk[p + 1] * xs[path_k[p + 1]];
    }
    if (p < depth_[k]) even += Lk[p] * xs[path_k[p]];
    xs[k] -= even + odd;
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
