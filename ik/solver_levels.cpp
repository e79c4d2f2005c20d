// The three levels of ik::Solver, each solved in the null space of the levels above it, in
// weight-scaled coordinates x (θ̇ = diag(c) x; ik/solver_workspace.hpp has the notation).
#include <algorithm>
#include <cassert>
#include <cmath>

#include "core/scaled_sum.hpp"
#include "ik/small_cholesky.hpp"
#include "ik/solver.hpp"

namespace ik {

void Solver::solve_levels(bool first_round) {
  // later range rounds of the same iteration only add range rows: level 1 is reused as is
  if (first_round) solve_drag_level();
  ws_.x = ws_.x_drag;
  solve_range_level();
  solve_pin_level(first_round);
  ws_.joint_velocity = ws_.x.cwiseProduct(ws_.joint_scale);
}

void Solver::solve_drag_level() {
  // x1 = J̃1ᵀ G⁻¹ v1 with J̃1 = J1 diag(c), G = J̃1 J̃1ᵀ; its null-space projector is
  // W1 = E − J̃1ᵀ G⁻¹ J̃1, applied implicitly by the levels below
  Workspace& w = ws_;
  const int m1 = w.drag_rows;
  report_.top_rows = m1;
  report_.top_damped = false;
  report_.top_rank = 0;
  if (m1 == 0) {
    w.x_drag.setZero();
    return;
  }
  auto J1 = w.drag_scaled.topRows(m1);
  J1 = w.drag_jacobian.topRows(m1).array().rowwise() * w.joint_scale.transpose().array();
  auto G = w.drag_gram.topLeftCorner(m1, m1);
  gram_lower(J1, G);
  auto t1 = w.drag_multipliers.head(m1);
  // exact pseudoinverse while every singular value of J̃1 exceeds the threshold
  const double s0 = settings_.top_singular_value;
  bool well_conditioned = cholesky_in_place(G);
  if (well_conditioned) {
    // σ_min² ≥ 1 / trace(G⁻¹) = 1 / |L⁻¹|²_F: a cheap lower bound on the smallest singular value
    auto Linv = w.drag_factor_inverse.topLeftCorner(m1, m1);
    Linv.setIdentity();
    forward_substitute(G, Linv);
    well_conditioned = Linv.squaredNorm() * s0 * s0 < 1.0;
  }
  w.drag_gram_factored = well_conditioned;
  if (well_conditioned) {
    t1 = w.drag_velocity.head(m1);
    cholesky_solve(G, t1);
    report_.top_rank = m1;
  } else {
    // the factorization overwrote G: form it again for the eigen-decomposition
    gram_lower(J1, G);
    invert_damped_drag_gram(G);
    t1.noalias() = w.drag_damped[m1]->inverse * w.drag_velocity.head(m1);
  }
  w.x_drag.noalias() = J1.transpose() * t1;
}

void Solver::invert_damped_drag_gram(const Eigen::Ref<const Eigen::MatrixXd>& G) {
  // damp only the directions whose singular value σ is below s0:
  // λ² = k (1 − σ²/s0²), G⁻¹ ≈ V diag(1 / (σ² + λ²)) Vᵀ
  const int m1 = ws_.drag_rows;
  DampedGramInverse& d = *ws_.drag_damped[m1];
  d.decompose(G);
  d.sigma2 = d.sigma2.cwiseMax(0.0);
  const double s02 = settings_.top_singular_value * settings_.top_singular_value;
  const double tol = 1e-12 * std::max(1.0, d.sigma2.maxCoeff());
  for (int k = 0; k < m1; ++k) {
    const double sigma2 = d.sigma2[k];
    const double lambda2 = sigma2 < s02 ? settings_.top_damping * (1.0 - sigma2 / s02) : 0.0;
    if (lambda2 > 0) report_.top_damped = true;
    const double denominator = sigma2 + lambda2;
    d.gain[k] = denominator > tol ? 1.0 / denominator : 0.0;
    if (sigma2 > tol) ++report_.top_rank;
  }
  d.scaled_vectors.noalias() = d.vectors * d.gain.asDiagonal();
  d.inverse.noalias() = d.scaled_vectors * d.vectors.transpose();
}

void Solver::solve_range_level() {
  // selection rows e_cᵀ diag(c), solved exactly (lightly damped) in the null space of the drag:
  // SR = JR W1, x2 = SRᵀ GR⁻¹ (vR − JR x1), with GR = SR SRᵀ + k E. Ranges outrank pins, so a
  // pinned link gives way before a joint leaves its range.
  Workspace& w = ws_;
  const int mR = w.range_rows, m1 = w.drag_rows;
  if (mR == 0) {
    w.x_range.setZero();
    return;
  }
  auto SR = w.range_projected.topRows(mR);
  SR.setZero();
  auto tR = w.range_multipliers.head(mR);
  for (int r = 0; r < mR; ++r) {
    const int c = w.range_coordinate[r];
    SR(r, c) = w.joint_scale[c];
    tR[r] = w.range_velocity[r] - w.joint_scale[c] * w.x[c];  // desired minus what the drag does
  }
  if (m1 > 0) {
    // SR = JR − (JR J̃1ᵀ) G⁻¹ J̃1: row r subtracts gᵀ J̃1 with g = G⁻¹ J̃1(:, c) c_c
    const auto J1 = w.drag_scaled.topRows(m1);
    auto column = w.range_drag_column.head(m1);
    auto g = w.range_drag_component.head(m1);
    for (int r = 0; r < mR; ++r) {
      const int c = w.range_coordinate[r];
      column = w.joint_scale[c] * J1.col(c);
      if (w.drag_gram_factored) {
        g = column;
        cholesky_solve(w.drag_gram.topLeftCorner(m1, m1), g);
      } else {
        g.noalias() = w.drag_damped[m1]->inverse * column;
      }
      SR.row(r).noalias() -= g.transpose() * J1;
    }
  }
  auto GR = w.range_gram.topLeftCorner(mR, mR);
  gram_lower(SR, GR);
  GR.diagonal().array() += std::max(settings_.range_damping, 1e-12);
  cholesky_in_place(GR);  // SPD: a Gram matrix plus a positive ridge
  cholesky_solve(GR, tR);
  w.x_range.noalias() = SR.transpose() * tR;
  w.x += w.x_range;
}

void Solver::solve_pin_level(bool first_round) {
  // Δ = argmin |J̃2 (x + Δ) − ṽ2|² + k |Δ|² over the Δ that leave levels 1 and 2 untouched
  // (C Δ = 0, C = [J̃1; SR]). This is the SR inverse y = S*(ṽ2 − J̃2 x) of S = J̃2 W with W the
  // projector of the levels above (Yamane eqs. 8.14–8.16), solved through its normal equations:
  // A = J̃2ᵀJ̃2 + kE has the tree's branch-induced sparsity (every row lives on one root path),
  // so it factorizes like the mass matrix (RBDA §6.5), and the constraint enters through the
  // small Schur complement C A⁻¹ Cᵀ. No N×N projector, no dense N³ work.
  Workspace& w = ws_;
  const int m2 = w.pin_rows;
  report_.lower_rows = m2;
  report_.lower_solution_norm = 0;
  report_.lower_rhs_norm = 0;
  if (m2 == 0) {
    w.x_pin.setZero();
    return;
  }
  // Every row lives on its link's root path or selects one coordinate (pin_row_support), so
  // only those entries of J̃2 are formed and read; the rest of pin_scaled is never used.
  auto J2 = w.pin_scaled.topRows(m2);
  const auto row_scale = w.pin_row_scale.head(m2);
  auto dp = w.pin_residual.head(m2);
  // Δṗ = ṽ2 − J̃2 x: what levels 1 and 2 leave to this level
  dp = w.pin_velocity.head(m2).cwiseProduct(row_scale);
  for (int r = 0; r < m2;) {
    const int support = w.pin_row_support[r];
    if (support < 0) {
      const int c = -1 - support;
      // scaled selection row: √weight × 1/√w at its coordinate
      if (first_round) J2(r, c) = row_scale[r] * w.joint_scale[c];
      dp[r] -= J2(r, c) * w.x[c];
      ++r;
      continue;
    }
    const int end = task_rows_end(r);
    const int m = end - r;
    // plain loops over the task's (at most 6) rows: Eigen's dynamic segments cost more to set up
    double* const dp_r = dp.data() + r;
    const double* const scale_r = row_scale.data() + r;
    for (const int c : w.link_path[support]) {
      double* const J2c = &J2(r, c);
      if (first_round) {
        // scaled rows: rows × √weight, columns × 1/√w
        const double* const Jc = &w.pin_jacobian(r, c);
        const double column_scale = w.joint_scale[c];
        for (int t = 0; t < m; ++t) J2c[t] = Jc[t] * scale_r[t] * column_scale;
      }
      const double xc = w.x[c];
      for (int t = 0; t < m; ++t) dp_r[t] -= J2c[t] * xc;
    }
    r = end;
  }
  if (first_round) factorize_pin_level();
  solve_pin_normal_equations();
  report_.lower_solution_norm = w.x_pin.norm();
  report_.lower_rhs_norm = dp.norm();
  w.x += w.x_pin;
}

void Solver::factorize_pin_level() {
  // A = J̃2ᵀ J̃2 + k E, then A = Lᵀ D L, in A's tree pattern alone (core::BranchSparseMatrix: the
  // entries A(j, c) for c and its ancestors j, along c's root path). The rows of one link task
  // share its root path: they are gathered along the path into a dense block P (its rows
  // contiguous) and Pᵀ P added a row prefix at a time (BranchSparseMatrix::add_path_gram).
  Workspace& w = ws_;
  const auto J2 = w.pin_scaled.topRows(w.pin_rows);
  core::BranchSparseMatrix& A = w.normal_matrix;
  A.set_zero();
  for (int r = 0; r < w.pin_rows;) {
    const int support = w.pin_row_support[r];
    if (support < 0) {
      const int c = -1 - support;
      A.diagonal(c) += J2(r, c) * J2(r, c);
      ++r;
      continue;
    }
    const int end = task_rows_end(r);
    const std::vector<int>& cols = w.link_path[support];
    const int n = static_cast<int>(cols.size());
    const int m = end - r;
    auto P = w.path_rows.topLeftCorner(m, n);
    for (int a = 0; a < n; ++a) P.col(a) = J2.col(cols[a]).segment(r, m);
    // cols is the root path of its last coordinate, root first: A's own path for that column
    assert(n == 0 || std::equal(cols.begin(), cols.end(), A.path(cols[n - 1])));
    if (n > 0) A.add_path_gram(cols[n - 1], P);
    r = end;
  }
  const double k = pin_damping();
  report_.lower_damping = k;
  for (int c = 0; c < model_.nv; ++c) A.diagonal(c) += k;
  A.factorize();
  for (int c = 0; c < model_.nv; ++c) w.pivot_inverse[c] = 1.0 / A.diagonal(c);
  w.constraint_columns = 0;
}

int Solver::task_rows_end(int r) const {
  // the rows of one link task follow each other (at most 6, the size of path_rows)
  const Workspace& w = ws_;
  const int support = w.pin_row_support[r];
  int end = r + 1;
  while (end < w.pin_rows && end - r < w.path_rows.rows() && w.pin_row_support[end] == support) {
    ++end;
  }
  return end;
}

double Solver::pin_damping() {
  // the SR inverse's k (Yamane eq. 8.7) under the chosen schedule; reads J̃2ᵀ J̃2 before the ridge
  Workspace& w = ws_;
  if (settings_.damping_schedule == DampingSchedule::kResidual) {
    // Sugihara's solvability-unconcerned damping (IEEE T-RO 2011): k grows with the squared
    // residual, so far-off (unreachable) targets are solved calmly and nearly met ones fast
    const double r2 = w.pin_residual.head(w.pin_rows).squaredNorm();
    const double v2 = kResidualDampingSpeed * kResidualDampingSpeed;
    return std::max(kMinimumDamping, settings_.damping * std::min(1.0, r2 / v2));
  }
  if (settings_.damping_schedule == DampingSchedule::kManipulability) {
    // w: geometric mean of the pivots of J̃2ᵀJ̃2 (the unprojected rows); damping grows below w0
    const int n = model_.nv;
    core::BranchSparseMatrix& pivots = w.manipulability_pivots;
    pivots = w.normal_matrix;  // as factorize_pin_level formed it, before the ridge
    for (int i = 0; i < n; ++i) pivots.diagonal(i) += 1e-12;
    pivots.factorize();
    double log_det = 0;
    for (int i = 0; i < n; ++i) log_det += std::log(pivots.diagonal(i));
    const double manipulability = std::exp(0.5 * log_det / n);
    const double w0 = settings_.manipulability_threshold;
    const double shortfall = 1 - manipulability / w0;
    return std::max(1e-12, manipulability < w0 ? settings_.damping * shortfall * shortfall : 0.0);
  }
  return settings_.damping;
}

void Solver::solve_pin_normal_equations() {
  // the unconstrained step u = A⁻¹ b with b = J̃2ᵀ Δṗ, then the correction that keeps C Δ = 0
  Workspace& w = ws_;
  const auto J2 = w.pin_scaled.topRows(w.pin_rows);
  const auto dp = w.pin_residual.head(w.pin_rows);
  // b, sparse like A
  w.normal_rhs.setZero();
  for (int r = 0; r < w.pin_rows;) {
    const int support = w.pin_row_support[r];
    if (support < 0) {
      w.normal_rhs[-1 - support] += J2(r, -1 - support) * dp[r];
      ++r;
      continue;
    }
    // a link task's rows at once: one walk along its path, a short column dot per coordinate
    const int end = task_rows_end(r);
    for (const int c : w.link_path[support]) {
      w.normal_rhs[c] += J2.col(c).segment(r, end - r).dot(dp.segment(r, end - r));
    }
    r = end;
  }
  const core::BranchSparseMatrix& A = w.normal_matrix;
  Eigen::VectorXd& y = w.x_pin;
  w.half_solved_rhs = w.normal_rhs;
  A.solve_lt(w.half_solved_rhs);  // L⁻ᵀ b
  const Eigen::VectorXd& Dinv = w.pivot_inverse;
  const int m1 = w.drag_rows;
  const int mc = m1 + w.range_rows;
  if (mc == 0) {
    y = w.half_solved_rhs.cwiseProduct(Dinv);
    A.solve_l(y);
    return;
  }
  // with A = Lᵀ D L: Z = L⁻ᵀ Cᵀ (half solves, each staying on its row's root path), then
  // C A⁻¹ Cᵀ = Zᵀ D⁻¹ Z and the correction A⁻¹ Cᵀ λ = L⁻¹ D⁻¹ Z λ. Columns of earlier rounds
  // are still valid.
  auto Z = w.constraint_half.topLeftCorner(model_.nv, mc);
  if (w.constraint_columns < mc) {
    for (int r = w.constraint_columns; r < mc; ++r) {
      Z.col(r) =
          r < m1 ? w.drag_scaled.row(r).transpose() : w.range_projected.row(r - m1).transpose();
    }
    A.solve_lt_columns(Z.rightCols(mc - w.constraint_columns));
    w.constraint_columns = mc;
  }
  auto Sc = w.constraint_schur.topLeftCorner(mc, mc);
  auto lambda = w.constraint_multipliers.head(mc);
  // Sc = Zᵀ D⁻¹ Z (+ a tiny ridge: when a range row repeats a drag direction the system is
  // singular but consistent, and the ridge picks the finite solution); λ = Sc⁻¹ Zᵀ D⁻¹ L⁻ᵀ b =
  // Sc⁻¹ C u. Both are sums over the rows of Z, and only the rows on the constrained rows' root
  // paths are nonzero. Sc is symmetric and its Cholesky factorization reads the lower triangle
  // alone, so only that is formed: column i from row i down, contiguous.
  for (int i = 0; i < mc; ++i) Sc.col(i).tail(mc - i).setZero();
  lambda.setZero();
  const Eigen::VectorXd& h = w.half_solved_rhs;
  for (int k = 0; k < model_.nv; ++k) {
    const double* const Zk = Z.data() + k * Z.outerStride();
    if (std::all_of(Zk, Zk + mc, [](double z) { return z == 0; })) continue;
    for (int i = 0; i < mc; ++i) {
      const double dz = Dinv[k] * Zk[i];
      core::add_scaled(&Sc(i, i), Zk + i, dz, mc - i);
      lambda[i] += dz * h[k];
    }
  }
  Sc.diagonal().array() += 1e-12 * std::max(1.0, Sc.diagonal().maxCoeff());
  if (cholesky_in_place(Sc)) {
    cholesky_solve(Sc, lambda);
  } else {
    lambda.setZero();  // cannot happen for a positive ridge; keep the unconstrained step bounded
  }
  // y = u − L⁻¹ D⁻¹ Z λ = L⁻¹ D⁻¹ (L⁻ᵀ b − Z λ)
  y = h;
  y.noalias() -= Z * lambda;
  y.array() *= Dinv.array();
  A.solve_l(y);
}

}  // namespace ik
