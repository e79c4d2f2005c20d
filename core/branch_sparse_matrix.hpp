// A symmetric matrix with a kinematic tree's branch-induced sparsity, stored column by column
// along each coordinate's root path, and its Lᵀ D L factorization.
#pragma once

#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/model.hpp"

namespace core {

/// A symmetric nv x nv matrix A whose entry (j, k) can be nonzero only when j is k or one of its
/// ancestors in Model::parent_v (the branch-induced sparsity of RBDA §6.5: J̃ᵀJ̃ for rows that each
/// live on one root path, or the joint-space inertia). Column k keeps those entries contiguously
/// in root-to-k order: ancestor j at position depth(j), the number of coordinates above j, and
/// k's own diagonal entry last. The ancestors of an ancestor i of k are then the prefix of k's
/// column up to depth(i), so each update of the factorization (RBDA Table 6.3) is a dense update of
/// a prefix of one column by a prefix of another, with no index lists and no gaps.
class BranchSparseMatrix {
 public:
  BranchSparseMatrix() = default;
  /// Sized for the model's coordinates (allocates); every entry zero.
  explicit BranchSparseMatrix(const Model& model);

  int size() const { return static_cast<int>(depth_.size()); }
  /// The number of coordinates above k: k's diagonal entry is column(k)[depth(k)].
  int depth(int k) const { return depth_[k]; }
  /// column(k)[p] = A(path(k)[p], k) for p = 0 … depth(k).
  double* column(int k) { return values_.data() + offset_[k]; }
  const double* column(int k) const { return values_.data() + offset_[k]; }
  /// path(k)[p]: the coordinate at depth p on k's root path; path(k)[depth(k)] = k.
  const int* path(int k) const { return path_.data() + offset_[k]; }
  double& diagonal(int k) { return values_[offset_[k] + depth_[k]]; }
  double diagonal(int k) const { return values_[offset_[k] + depth_[k]]; }

  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  void set_zero();
  /// A += PᵀP for rows P that live on leaf's root path: column a of P belongs to path(leaf)[a]
  /// (P has depth(leaf) + 1 columns). The normal matrix of a task whose rows share one path.
  void add_path_gram(int leaf, const Eigen::Ref<const RowMajorMatrix>& P);
  /// In place A = Lᵀ D L (RBDA Table 6.3), L unit lower triangular with the same sparsity: L(k, j)
  /// is written over A(j, k), D over the diagonal. A must be positive definite. Allocation-free.
  /// A column whose entries above the diagonal are all zero when it is eliminated (a coordinate
  /// no row of a normal matrix touches beyond its diagonal) updates nothing: it and its share of
  /// the solves below are skipped.
  void factorize();
  /// After factorize(): whether L(k, j) is nonzero for some ancestor j of k.
  bool coupled(int k) const { return coupled_[k] != 0; }
  /// x ← L⁻ᵀ x, after factorize().
  void solve_lt(Eigen::Ref<Eigen::VectorXd> x) const;
  /// X ← L⁻ᵀ X for all columns of X at once (its rows contiguous); rows that stay zero cost a test.
  void solve_lt_columns(Eigen::Ref<RowMajorMatrix> X) const;
  /// x ← L⁻¹ x, after factorize().
  void solve_l(Eigen::Ref<Eigen::VectorXd> x) const;
  /// The entries as a dense symmetric matrix (zeros off the pattern): for tests and printing.
  Eigen::MatrixXd dense() const;

 private:
  static constexpr int kMaxChainBlock = 3;  // columns factorized together (factorize())

  std::vector<int> offset_;  // where column k starts in values_ and path_
  std::vector<int> depth_;
  std::vector<int> path_;
  std::vector<int> parent_;       // Model::parent_v
  std::vector<int> chain_start_;  // Model::chain_start_v: the solves walk the ancestors by runs
  std::vector<double> values_;
  std::vector<char> coupled_;  // per column, set by factorize(): L(k, ·) has a nonzero entry
  std::vector<std::pair<int, int>> chain_blocks_;  // (lo, hi), hi descending: factorize()'s order
};

}  // namespace core
