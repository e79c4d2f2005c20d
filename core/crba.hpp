// Composite-rigid-body algorithm and the tree-sparse factorization of the joint-space inertia.
#pragma once

#include <Eigen/Core>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Joint-space inertia H(q) with τ = H(q) a + b(q, v). RBDA §6.2; cross-checked against rnea()
/// columns in tests/core/dynamics_test.cpp (Crba.MatchesRneaColumns).
/// @return data.M (nv x nv), full symmetric matrix; also fills data.X_P, data.Ic, data.crba_X_W
///         and data.crba_S (not data.X_W or data.J)
const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q);

/// Factorizes H = Lᵀ D L exploiting branch-induced sparsity (RBDA §6.5, Table 6.3): L is zero
/// wherever the coordinates are not on one root-to-leaf path, and the work is O(n d²) for depth d.
/// Requires: crba(model, data, q). Writes data.LTDL.
void factorize_mass_matrix(const Model& model, Data& data);

/// The same factorization for any symmetric positive definite matrix with the tree's
/// branch-induced sparsity (entry (i, j) nonzero only when one coordinate is an ancestor of the
/// other in Model::parent_v): in place, lower triangle read, L written over both triangles (the
/// upper as Lᵀ) and D over the diagonal; the solves below read L from the upper triangle.
void ltdl_factorize(const Model& model, Eigen::Ref<Eigen::MatrixXd> H);
/// ltdl_factorize on the upper triangle alone: H(j, k) read for k's ancestors j (and the
/// diagonal), L written there, nothing else read or written; the solves below read it as is.
/// (core::BranchSparseMatrix stores only those positions, for matrices formed there.)
void ltdl_factorize_upper(const Model& model, Eigen::Ref<Eigen::MatrixXd> H);
/// x ← H⁻¹ x with a matrix factorized by ltdl_factorize.
void ltdl_solve(const Model& model,
                const Eigen::Ref<const Eigen::MatrixXd>& LTDL,
                Eigen::Ref<Eigen::VectorXd> x);
/// x ← L⁻¹ x (the last part of ltdl_solve, after the division by D).
void ltdl_solve_l(const Model& model,
                  const Eigen::Ref<const Eigen::MatrixXd>& LTDL,
                  Eigen::Ref<Eigen::VectorXd> x);
/// x ← L⁻ᵀ x (the first half of ltdl_solve).
void ltdl_solve_lt(const Model& model,
                   const Eigen::Ref<const Eigen::MatrixXd>& LTDL,
                   Eigen::Ref<Eigen::VectorXd> x);

/// Solves H x = b in place with the factorization (RBDA Table 6.4). Allocation-free.
/// Requires: factorize_mass_matrix(model, data).
void solve_mass_matrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> b);

/// The same for every column of B.
void solve_mass_matrix_columns(const Model& model, const Data& data, Eigen::Ref<Eigen::MatrixXd> B);

/// X ← L⁻ᵀ X in place for columns that are zero off the root path ending at coordinate `last`
/// (Model::path_last_v): the columns of Jᵀ for one point's Jacobian rows. Walks that path alone,
/// each entry of L loaded once for all the columns. Allocation-free.
/// Requires: factorize_mass_matrix(model, data).
void solve_mass_matrix_lt_on_path(const Model& model,
                                  const Data& data,
                                  int last,
                                  Eigen::Ref<Eigen::MatrixXd> X);

/// y = L⁻ᵀ x in place (x is overwritten): the half solve used for J H⁻¹ Jᵀ = Yᵀ D⁻¹ Y.
void solve_mass_matrix_lt(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x);

}  // namespace core
