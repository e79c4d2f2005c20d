// Scratch space of ik::Solver: every matrix and vector one step needs, grouped by the level it
// serves. The constructor sizes what depends on the model, reserve() what depends on the
// problem's row counts; both only grow, so once a problem of some size has been seen, steps
// on problems of that size allocate nothing.
//
// Notation (Yamane ch. 8, docs/ik.md): the solver works in weight-scaled joint coordinates x,
// θ̇ = diag(c) x with c_j = 1/√w_j, so a task Jacobian J becomes J̃ = J diag(c). Level 1 is the
// drag (J1 θ̇ = v1), level 2 the joint ranges, level 3 the pins and references (J2 θ̇ = v2); each
// is solved in the null space of the levels above it.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "core/branch_sparse_matrix.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"
#include "ik/limits.hpp"

namespace ik {

/// G⁻¹ for a drag level that loses rank (fixed root, stretched limb), damped only along the
/// directions whose singular value σ is below σ0: G⁻¹ ≈ V diag(1/(σ² + λ²)) Vᵀ with
/// λ² = k (1 − σ²/σ0²) (docs/ik.md, question 2). Sized for one row count m; the workspace keeps
/// one per row count seen.
struct DampedGramInverse {
  explicit DampedGramInverse(int rows);
  /// G = V diag(σ²) Vᵀ, σ² ascending: the steps of Eigen::SelfAdjointEigenSolver::compute
  /// (scale, tridiagonalize, accumulate Q, implicit QR), with the Householder workspace that
  /// compute() allocates on every call kept here instead.
  void decompose(const Eigen::Ref<const Eigen::MatrixXd>& G);

  Eigen::MatrixXd vectors;      // V, orthonormal eigenvectors by column (m x m)
  Eigen::VectorXd sigma2;       // σ² of each direction (m)
  Eigen::VectorXd subdiagonal;  // the tridiagonal form's subdiagonal, then scratch (m − 1)
  Eigen::VectorXd householder;  // Householder coefficients of the tridiagonalization (m − 1)
  Eigen::VectorXd reflector_scratch;  // workspace for applying the reflectors (m)
  Eigen::VectorXd gain;               // 1/(σ² + λ²), 0 for directions below the rank tolerance
  Eigen::MatrixXd scaled_vectors;     // V diag(gain)
  Eigen::MatrixXd inverse;            // V diag(gain) Vᵀ ≈ G⁻¹
};

struct Workspace {
  explicit Workspace(const core::Model& model);
  /// Grows the buffers for a problem with these row counts on levels 1 and 3.
  void reserve(int top_rows, int lower_rows);

  // --- all levels; nv entries each ---
  Eigen::VectorXd joint_scale;     // c_j = 1/√w_j (0 locks joint j), so J̃ = J diag(c)
  Eigen::VectorXd x;               // the step being assembled, θ̇ = diag(c) x
  Eigen::VectorXd x_drag;          // level 1's part of x
  Eigen::VectorXd x_range;         // level 2's part of x
  Eigen::VectorXd x_pin;           // level 3's part of x: the SR solution y (eqs. 8.14–8.16)
  Eigen::VectorXd joint_velocity;  // θ̇ = diag(c) x of the last iteration

  // --- level 1, the drag: x1 = J̃1ᵀ G⁻¹ v1 with G = J̃1 J̃1ᵀ (weighted pseudoinverse, §8.2.4);
  //     m1 rows ---
  int drag_rows = 0;                    // m1
  Eigen::MatrixXd drag_jacobian;        // J1, world-aligned rows of the kTop tasks (m1 x nv)
  Eigen::VectorXd drag_velocity;        // v1 = ṙ_ref + K (r_ref − r) (eq. 8.8)
  Eigen::MatrixXd drag_scaled;          // J̃1 = J1 diag(c) (m1 x nv)
  Eigen::MatrixXd drag_gram;            // G = J̃1 J̃1ᵀ, then its Cholesky factor L (m1 x m1)
  Eigen::MatrixXd drag_factor_inverse;  // L⁻¹, for the bound σ_min² ≥ 1/|L⁻¹|²_F (m1 x m1)
  bool drag_gram_factored = true;       // drag_gram holds L; else drag_damped[m1] holds G⁻¹
  Eigen::VectorXd drag_multipliers;     // G⁻¹ v1
  std::vector<std::optional<DampedGramInverse>> drag_damped;  // by m1, for when J1 loses rank

  // --- level 2, joint ranges: selection rows e_cᵀ θ̇ = vR (eqs. 8.17–8.20, 8.23, §8.3.5),
  //     SR = JR W1 with W1 the drag's null-space projector, x2 = SRᵀ GR⁻¹ (vR − JR x1);
  //     mR rows, at most one block per joint ---
  int range_rows = 0;                    // mR
  std::vector<RangeRow> range_blocks;    // the joints with rows this iteration (ik/limits.hpp)
  std::vector<char> range_flagged;       // per joint: already has a row (njoints)
  std::vector<int> range_coordinate;     // per row: the velocity coordinate it selects
  Eigen::VectorXd range_velocity;        // vR
  Eigen::MatrixXd range_projected;       // SR = JR − (JR J̃1ᵀ) G⁻¹ J̃1 (mR x nv)
  Eigen::VectorXd range_drag_column;     // J̃1 e_c c_c, one range row seen by level 1 (m1)
  Eigen::VectorXd range_drag_component;  // G⁻¹ J̃1 e_c c_c (m1)
  Eigen::MatrixXd range_gram;            // GR = SR SRᵀ + kR E, then its Cholesky factor
  Eigen::VectorXd range_multipliers;     // GR⁻¹ (vR − JR x1)

  // --- level 3, pins and references: the SR inverse y = S*(ṽ2 − J̃2 x) of S = J̃2 W, W the
  //     projector of levels 1 and 2 (eqs. 8.7, 8.14–8.16), through the normal equations
  //     A Δ = J̃2ᵀ (ṽ2 − J̃2 x), A = J̃2ᵀ J̃2 + kE, subject to C Δ = 0 with C = [J̃1; SR];
  //     m2 rows, mc = m1 + mR constraint rows ---
  int pin_rows = 0;                  // m2
  Eigen::MatrixXd pin_jacobian;      // J2, rows of the kLower tasks (m2 x nv)
  Eigen::VectorXd pin_velocity;      // v2 (eqs. 8.21, 8.22, 8.24–8.26, 8.30, 8.31)
  Eigen::VectorXd pin_row_scale;     // √weight of each row (W_e^{1/2})
  std::vector<int> pin_row_support;  // per row: its link (>= 0), or −1 − the coordinate it selects
  std::vector<std::vector<int>> link_path;  // per link: coordinates on its root path, ascending
  Eigen::MatrixXd pin_scaled;               // J̃2 = diag(√weight) J2 diag(c) (m2 x nv)
  Eigen::VectorXd pin_residual;             // Δṗ = ṽ2 − J̃2 x, what levels 1 and 2 leave
  // A = J̃2ᵀ J̃2 + kE, then its tree-sparse Lᵀ D L, stored along each coordinate's root path
  core::BranchSparseMatrix normal_matrix;
  Eigen::VectorXd pivot_inverse;  // D⁻¹ of that factorization (nv)
  // one task's rows of J̃2 gathered along its link's path, rows contiguous (6 x nv)
  core::BranchSparseMatrix::RowMajorMatrix path_rows;
  core::BranchSparseMatrix manipulability_pivots;  // Lᵀ D L of J̃2ᵀ J̃2, w = (Π D)^(1/2n)
  Eigen::VectorXd normal_rhs;                      // b = J̃2ᵀ Δṗ (nv)
  Eigen::VectorXd half_solved_rhs;                 // L⁻ᵀ b (nv)
  // Z = L⁻ᵀ Cᵀ, one column per row of C, row-major: the solves update rows (nv x mc)
  core::BranchSparseMatrix::RowMajorMatrix constraint_half;
  int constraint_columns = 0;        // columns of Z valid for the current factorization
  Eigen::MatrixXd constraint_schur;  // C A⁻¹ Cᵀ = Zᵀ D⁻¹ Z, then its Cholesky factor
  Eigen::VectorXd constraint_multipliers;  // λ = (C A⁻¹ Cᵀ)⁻¹ C A⁻¹ b
};

}  // namespace ik
