#include "ik/solver.hpp"

#include "ik/small_cholesky.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/kinematics.hpp"

namespace ik {

namespace {

double gain_or(double g, double fallback) { return g >= 0 ? g : fallback; }

bool positive_finite(double x) { return std::isfinite(x) && x > 0; }

// rows a range block of joint i contributes
int range_block_rows(const core::Model& m, int i) {
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic: return 1;
    case core::JointType::kSpherical: return m.spherical_range[i].empty() ? 0 : 3;
    default: return 0;
  }
}

}  // namespace

std::string validate(const SolverSettings& s) {
  if (!positive_finite(s.dt)) return "dt must be a finite number > 0";
  if (s.iterations < 1 || s.iterations > 1000) return "iterations must be in [1, 1000]";
  if (!std::isfinite(s.damping) || s.damping < 0) return "damping must be finite and >= 0";
  if (!std::isfinite(s.top_damping) || s.top_damping < 0) return "top_damping must be finite and >= 0";
  if (!std::isfinite(s.top_singular_value) || s.top_singular_value < 0)
    return "top_singular_value must be finite and >= 0";
  if (!positive_finite(s.manipulability_threshold)) return "manipulability_threshold must be > 0";
  for (const auto& [name, g] : {std::pair{"drag_gain", s.drag_gain}, {"pin_gain", s.pin_gain},
                                {"reference_gain", s.reference_gain}, {"limit_gain", s.limit_gain},
                                {"range_gain", s.range_gain}, {"range_damping", s.range_damping}}) {
    if (!std::isfinite(g) || g < 0) return std::string(name) + " must be finite and >= 0";
  }
  if (!positive_finite(s.max_position_error)) return "max_position_error must be > 0";
  if (!positive_finite(s.max_orientation_error)) return "max_orientation_error must be > 0";
  if (!std::isfinite(s.limit_margin) || s.limit_margin < 0) return "limit_margin must be >= 0";
  if (!positive_finite(s.max_joint_step)) return "max_joint_step must be > 0";
  return {};
}

Solver::Solver(const core::Model& model, const SolverSettings& settings)
    : model_(model),
      settings_(settings),
      col_scale_(Eigen::VectorXd::Ones(model.nv)),
      y_(Eigen::VectorXd::Zero(model.nv)),
      qdot_(Eigen::VectorXd::Zero(model.nv)),
      scaled_(Eigen::VectorXd::Zero(model.nv)),
      x_top_(Eigen::VectorXd::Zero(model.nv)),
      x_range_(Eigen::VectorXd::Zero(model.nv)),
      x_lower_(Eigen::VectorXd::Zero(model.nv)),
      point_(model.nv),
      range_flags_(model.njoints, 0) {
  int range_capacity = 0;
  for (int i = 1; i < model.njoints; ++i) range_capacity += range_block_rows(model, i);
  range_rows_.reserve(model.njoints);
  vR_.resize(range_capacity);
  // the velocity coordinates on each link's path to the root, ascending (a link task's row can
  // only touch these, so the lower level's normal matrix has the tree's sparsity)
  link_support_.resize(model.njoints);
  for (int i = 1; i < model.njoints; ++i) {
    for (int j = i; j > 0; j = model.parent[j]) {
      for (int d = core::joint_nv(model.joint_type[j]) - 1; d >= 0; --d) {
        link_support_[i].push_back(model.idx_v[j] + d);
      }
    }
    std::reverse(link_support_[i].begin(), link_support_[i].end());
  }
  A_.resize(model.nv, model.nv);
  b_.resize(model.nv);
  range_coord_.resize(range_capacity);
}

std::string Solver::check_problem(const Problem& problem, const Eigen::VectorXd& q) const {
  const core::Model& m = model_;
  if (q.size() != m.nq || !q.allFinite()) return "configuration has the wrong size or is not finite";
  const std::string settings_error = validate(settings_);
  if (!settings_error.empty()) return "settings: " + settings_error;
  auto finite_gain = [](double g) { return std::isfinite(g); };
  for (const auto& e : problem.entries()) {
    const std::string who = "task " + std::to_string(e.id);
    auto check_link_task = [&](const auto& t, const char* kind) -> std::string {
      if (t.link < 1 || t.link >= m.njoints) return who + " (" + kind + "): link index out of range";
      if (!t.target_W.allFinite() || !t.p_LinkPoint.allFinite() || !t.velocity_W.allFinite() ||
          !t.angular_velocity_W.allFinite())
        return who + " (" + kind + ", link '" + m.link_name[t.link] + "'): target is not finite";
      if (!t.target_R_W.coeffs().allFinite() || std::abs(t.target_R_W.norm() - 1.0) > 1e-6)
        return who + " (" + kind + ", link '" + m.link_name[t.link] + "'): rotation is not a unit quaternion";
      if (!finite_gain(t.gain) || !std::isfinite(t.weight) || t.weight < 0)
        return who + " (" + kind + "): gain and weight must be finite, weight >= 0";
      return {};
    };
    std::string err;
    if (const auto* d = std::get_if<DragTask>(&e.task)) err = check_link_task(*d, "drag");
    if (const auto* p = std::get_if<PinTask>(&e.task)) err = check_link_task(*p, "pin");
    if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
      if (r->joint < 1 || r->joint >= m.njoints) err = who + " (reference): joint index out of range";
      else if (!std::isfinite(r->q_ref) || !std::isfinite(r->velocity_ref) ||
               !r->R_ref.coeffs().allFinite() || !r->angular_velocity_ref.allFinite() ||
               !finite_gain(r->gain) || !std::isfinite(r->weight) || r->weight < 0)
        err = who + " (reference, joint '" + m.joint_name[r->joint] + "'): values are not finite";
    }
    if (!err.empty()) return err;
  }
  return {};
}

const Report& Solver::step(const Problem& problem, core::Data& data, Eigen::VectorXd& q) {
  const auto t0 = std::chrono::steady_clock::now();
  const core::Model& m = model_;
  report_.message = check_problem(problem, q);
  report_.status = report_.message.empty() ? Report::Status::kOk : Report::Status::kRejected;
  if (report_.status == Report::Status::kRejected) return report_;
  const double h = settings_.dt / settings_.iterations;

  // size the workspace for this problem (only grows)
  int top_task_rows = 0, lower_task_rows = 0;
  for (const auto& e : problem.entries()) {
    const int r = std::visit([&](const auto& t) { return task_rows(m, t); }, e.task);
    (e.priority == kTop ? top_task_rows : lower_task_rows) += r;
  }
  if (J1_.rows() < top_task_rows) {
    J1_.resize(top_task_rows, m.nv);
    v1_.resize(top_task_rows);
  }
  if (J2_.rows() < lower_task_rows) {
    J2_.resize(lower_task_rows, m.nv);
    v2_.resize(lower_task_rows);
    row_scale2_.resize(lower_task_rows);
    row_support_.resize(lower_task_rows);
  }
  for (int j = 0; j < m.nv; ++j) {
    const double w = settings_.use_joint_weights ? m.ik_weight[m.joint_of_v[j]] : 1.0;
    col_scale_[j] = w > 0 ? 1.0 / std::sqrt(w) : 0.0;  // weight 0 locks the joint
  }

  report_.max_joint_speed = 0;
  report_.step_limited = false;
  for (int it = 0; it < settings_.iterations; ++it) {
    core::compute_joint_jacobians(m, data, q);
    fill_rows(problem, data, q);
    // rows for joints already outside their ranges (Yamane eq. 8.23, §8.3.5)
    range_rows_.clear();
    std::fill(range_flags_.begin(), range_flags_.end(), 0);
    if (problem.enforce_ranges) {
      collect_range_violations(m, q, settings_.limit_gain, settings_.range_gain, range_rows_,
                               range_flags_);
    }
    mR_ = 0;
    append_range_rows(0);
    solve_levels(true);
    // rows for joints this step would carry out of range: stop them at the boundary and solve
    // again, until no further joint would leave its range (an active-set pass per round)
    for (int round = 0; problem.enforce_ranges && round < kMaxRangeRounds; ++round) {
      const size_t before = range_rows_.size();
      if (collect_range_predictions(m, q, qdot_, h, settings_.limit_margin, range_rows_,
                                    range_flags_) == 0) {
        break;
      }
      append_range_rows(before);
      solve_levels(false);
    }
    report_.range_rows = mR_;
    limit_step(h);
    report_.max_joint_speed = std::max(report_.max_joint_speed, qdot_.cwiseAbs().maxCoeff());
    core::integrate(m, q, qdot_, h, q);
  }
  core::forward_kinematics(m, data, q);
  fill_report(problem, data, q);
  report_.iterations = settings_.iterations;
  report_.microseconds =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  return report_;
}

void Solver::fill_rows(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q) {
  const core::Model& m = model_;
  const ErrorClamp clamp{settings_.max_position_error, settings_.max_orientation_error};
  m1_ = 0;
  m2_ = 0;
  for (const auto& e : problem.entries()) {
    const bool top = e.priority == kTop;
    Eigen::MatrixXd& J = top ? J1_ : J2_;
    Eigen::VectorXd& v = top ? v1_ : v2_;
    int& row = top ? m1_ : m2_;
    double weight = 1.0;
    int rows = 0;
    if (const auto* d = std::get_if<DragTask>(&e.task)) {
      rows = task_rows(m, *d);
      fill_link_task(m, data, d->link, d->p_LinkPoint, d->mode, d->target_W, d->target_R_W,
                     d->velocity_W, d->angular_velocity_W, gain_or(d->gain, settings_.drag_gain),
                     clamp, point_, J.middleRows(row, rows), v.segment(row, rows));
      weight = d->weight;
    } else if (const auto* p = std::get_if<PinTask>(&e.task)) {
      rows = task_rows(m, *p);
      fill_link_task(m, data, p->link, p->p_LinkPoint, p->mode, p->target_W, p->target_R_W,
                     p->velocity_W, p->angular_velocity_W, gain_or(p->gain, settings_.pin_gain),
                     clamp, point_, J.middleRows(row, rows), v.segment(row, rows));
      weight = p->weight;
    } else if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
      rows = task_rows(m, *r);
      const double K = gain_or(r->gain, m.ik_gain[r->joint].value_or(settings_.reference_gain));
      fill_reference_task(m, q, *r, K, clamp, J.middleRows(row, rows), v.segment(row, rows));
      weight = r->weight;
    }
    if (!top) {
      row_scale2_.segment(row, rows).setConstant(std::sqrt(std::max(0.0, weight)));
      // which coordinates each lower row can touch: the link's root path, or one coordinate
      for (int k = 0; k < rows; ++k) {
        if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
          row_support_[row + k] = -1 - (m.idx_v[r->joint] + k);
        } else {
          row_support_[row + k] = std::visit([](const auto& t) {
            if constexpr (requires { t.link; }) return t.link;
            return 0;
          }, e.task);
        }
      }
    }
    row += rows;
  }
}

namespace {
// largest α in [0, 1] with |a_j + α c_j| <= V for every j (given |a_j| <= V)
double admissible_fraction(const Eigen::VectorXd& a, const Eigen::VectorXd& c,
                           const Eigen::VectorXd& scale, double V) {
  double alpha = 1.0;
  for (Eigen::Index j = 0; j < a.size(); ++j) {
    const double aj = scale[j] * a[j], cj = scale[j] * c[j];
    if (cj == 0) continue;
    const double room = cj > 0 ? V - aj : V + aj;
    alpha = std::min(alpha, std::max(0.0, room / std::abs(cj)));
  }
  return alpha;
}
}  // namespace

void Solver::limit_step(double h) {
  // trust region: the linearization holds only for small steps, so no coordinate may move more
  // than max_joint_step in one iteration. The lower levels give way first (their contribution
  // is shortened), so the drag keeps its progress whenever it fits on its own.
  const double V = settings_.max_joint_step / h;
  if ((qdot_.cwiseAbs().array() <= V).all()) return;
  report_.step_limited = true;
  Eigen::VectorXd& a = scaled_;  // running sum of the levels kept so far
  const Eigen::VectorXd* levels[3] = {&x_top_, &x_range_, &x_lower_};
  a.setZero();
  for (const Eigen::VectorXd* level : levels) {
    if ((a.cwiseProduct(col_scale_).cwiseAbs().array() > V).any()) break;
    a += admissible_fraction(a, *level, col_scale_, V) * *level;
  }
  if ((a.cwiseProduct(col_scale_).cwiseAbs().array() > V).any()) {
    a *= V / a.cwiseProduct(col_scale_).cwiseAbs().maxCoeff();  // cannot happen after the top
  }
  qdot_ = a.cwiseProduct(col_scale_);
}

void Solver::append_range_rows(size_t first) {
  // range rows select joint coordinates (Yamane eqs. 8.17–8.20): keep the coordinate index only
  for (size_t k = first; k < range_rows_.size(); ++k) {
    const RangeRow& r = range_rows_[k];
    for (int d = 0; d < r.rows; ++d) {
      range_coord_[mR_] = model_.idx_v[r.joint] + d;
      vR_[mR_] = r.desired[d];
      ++mR_;
    }
  }
}

void Solver::solve_levels(bool first_round) {
  const int n = model_.nv;
  const auto col = col_scale_.transpose().array();
  Eigen::VectorXd& x = scaled_;  // solution in weight-scaled coordinates: θ̇ = diag(col) x

  // level 1, the drag: x = J̃1ᵀ G⁻¹ v1 with J̃1 = J1 diag(col), G = J̃1 J̃1ᵀ; its null-space
  // projector is W1 = E − J̃1ᵀ G⁻¹ J̃1. Later range rounds of the same iteration
  // only add range rows, so they reuse level 1 and the factorized lower level.
  if (!first_round) {
    x = x_top_;
  } else {
  report_.top_rows = m1_;
  report_.top_damped = false;
  report_.top_rank = 0;
  x.setZero();
  if (m1_ > 0) {
    if (J1s_.rows() < m1_ || J1s_.cols() != n) J1s_.resize(m1_, n);
    if (G_.rows() < m1_) G_.resize(m1_, m1_);
    if (E_.rows() < m1_) E_.resize(m1_, m1_);
    if (t_.size() < std::max(m1_, mR_)) t_.resize(std::max(m1_, mR_));
    auto J1 = J1s_.topRows(m1_);
    J1 = J1_.topRows(m1_).array().rowwise() * col;
    auto G = G_.topLeftCorner(m1_, m1_);
    G.setZero();
    G.selfadjointView<Eigen::Lower>().rankUpdate(J1);
    auto t1 = t_.head(m1_);
    // exact pseudoinverse while every singular value of J̃1 exceeds the threshold
    const double s0 = settings_.top_singular_value;
    bool well_conditioned = cholesky_in_place(G);
    if (well_conditioned) {
      // σ_min² ≥ 1 / trace(G⁻¹) = 1 / |L⁻¹|²_F: a cheap lower bound on the smallest singular value
      auto Linv = E_.topLeftCorner(m1_, m1_);
      Linv.setIdentity();
      forward_substitute(G, Linv);
      well_conditioned = Linv.squaredNorm() * s0 * s0 < 1.0;
    }
    top_is_cholesky_ = well_conditioned;
    if (well_conditioned) {
      t1 = v1_.head(m1_);
      cholesky_solve(G, t1);
      report_.top_rank = m1_;
    } else {
      // damp only the directions whose singular value σ is below s0:
      // λ² = k (1 − σ²/s0²), G⁻¹ ≈ V diag(1 / (σ² + λ²)) Vᵀ
      G.setZero();
      G.selfadjointView<Eigen::Lower>().rankUpdate(J1);
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G);
      const Eigen::VectorXd sigma2 = es.eigenvalues().cwiseMax(0.0);
      Eigen::VectorXd inv(m1_);
      const double s02 = s0 * s0;
      const double tol = 1e-12 * std::max(1.0, sigma2.maxCoeff());
      for (int k = 0; k < m1_; ++k) {
        const double lambda2 = sigma2[k] < s02 ? settings_.top_damping * (1.0 - sigma2[k] / s02) : 0.0;
        if (lambda2 > 0) report_.top_damped = true;
        const double d = sigma2[k] + lambda2;
        inv[k] = d > tol ? 1.0 / d : 0.0;
        if (sigma2[k] > tol) ++report_.top_rank;
      }
      Ginv_ = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
      t1.noalias() = Ginv_ * v1_.head(m1_);
    }
    x.noalias() = J1.transpose() * t1;
  }
  x_top_ = x;
  }

  // level 2, the joint ranges: selection rows e_cᵀ diag(col), solved exactly (lightly damped)
  // in the null space of the drag: SR = JR W1, y = SRᵀ GR⁻¹ (vR − JR x), with GR = SR SRᵀ + k E.
  // Ranges outrank pins, so a pinned link gives way before a joint leaves its range.
  if (mR_ > 0) {
    if (SR_.rows() < mR_ || SR_.cols() != n) SR_.resize(mR_, n);
    if (PR_.rows() < mR_ || PR_.cols() != n) PR_.resize(mR_, n);
    if (GR_.rows() < mR_) GR_.resize(mR_, mR_);
    if (t_.size() < std::max(m1_, mR_)) t_.resize(std::max(m1_, mR_));
    auto SR = SR_.topRows(mR_);
    SR.setZero();
    auto tR = t_.head(mR_);
    for (int r = 0; r < mR_; ++r) {
      const int c = range_coord_[r];
      SR(r, c) = col_scale_[c];
      tR[r] = vR_[r] - col_scale_[c] * x[c];  // desired minus what the drag already does
    }
    if (m1_ > 0) {
      // SR = JR W1 = JR − (JR J̃1ᵀ) G⁻¹ J̃1: row r subtracts wᵀ J̃1 with w = G⁻¹ J̃1(:, c) col_c
      if (w_.size() < m1_) w_.resize(m1_);
      for (int r = 0; r < mR_; ++r) {
        const int c = range_coord_[r];
        auto w = w_.head(m1_);
        w = col_scale_[c] * J1s_.topRows(m1_).col(c);
        if (top_is_cholesky_) {
          cholesky_solve(G_.topLeftCorner(m1_, m1_), w);
        } else {
          w = Ginv_ * w;
        }
        SR.row(r).noalias() -= w.transpose() * J1s_.topRows(m1_);
      }
    }
    auto GR = GR_.topLeftCorner(mR_, mR_);
    GR.setZero();
    GR.selfadjointView<Eigen::Lower>().rankUpdate(SR);
    GR.diagonal().array() += std::max(settings_.range_damping, 1e-12);
    cholesky_in_place(GR);  // SPD: a Gram matrix plus a positive ridge
    auto PR = PR_.topRows(mR_);
    PR = SR;
    cholesky_solve(GR, PR);
    cholesky_solve(GR, tR);
    x_range_.noalias() = SR.transpose() * tR;
    x += x_range_;
  } else {
    x_range_.setZero();
  }

  // level 3, pins and references: Δ = argmin |J̃2 (x + Δ) − ṽ2|² + k |Δ|² over the Δ that leave
  // the levels above untouched (C Δ = 0, C = [J̃1; JR]). This is the SR inverse y = S*(ṽ2 − J̃2 x)
  // of S = J̃2 W with W the projector of the levels above (Yamane eq. 8.14–8.16), solved through
  // its normal equations: A = J̃2ᵀJ̃2 + kE has the tree's branch-induced sparsity (every row lives
  // on one root path), so it factorizes like the mass matrix (RBDA §6.5), and the constraint
  // enters through the small Schur complement C A⁻¹ Cᵀ. No N×N projector, no dense N³ work.
  report_.lower_rows = m2_;
  report_.lower_solution_norm = 0;
  report_.lower_rhs_norm = 0;
  if (m2_ > 0) {
    if (dp_.size() < m2_) dp_.resize(m2_);
    auto dp = dp_.head(m2_);
    if (J2s_.rows() < m2_ || J2s_.cols() != n) J2s_.resize(m2_, n);
    auto J2 = J2s_.topRows(m2_);
    if (first_round) {
      // scaled rows (rows × √weight, columns × 1/√w) and A = J̃2ᵀ J̃2 + k E (lower triangle),
      // row by row over each row's support
      J2 = (J2_.topRows(m2_).array().rowwise() * col).colwise() * row_scale2_.head(m2_).array();
      A_.setZero();
      for (int r = 0; r < m2_; ++r) {
        const int sup = row_support_[r];
        if (sup < 0) {
          const int c = -1 - sup;
          A_(c, c) += J2(r, c) * J2(r, c);
          continue;
        }
        const std::vector<int>& cols = link_support_[sup];
        for (size_t a = 0; a < cols.size(); ++a) {
          const double ja = J2(r, cols[a]);
          if (ja == 0) continue;
          for (size_t c = 0; c <= a; ++c) A_(cols[a], cols[c]) += ja * J2(r, cols[c]);
        }
      }
      double k = settings_.damping;
      if (settings_.damping_schedule == DampingSchedule::kResidual) {
        // Sugihara's solvability-unconcerned damping (IEEE T-RO 2011): k grows with the squared
        // residual, so far-off (unreachable) targets are solved calmly and nearly met ones fast
        const double r2 = (v2_.head(m2_).cwiseProduct(row_scale2_.head(m2_)) - J2 * x).squaredNorm();
        k = std::max(kMinimumDamping, settings_.damping * std::min(1.0, r2 / (kResidualDampingSpeed * kResidualDampingSpeed)));
      } else if (settings_.damping_schedule == DampingSchedule::kManipulability) {
        // w: geometric mean of the pivots of J̃2ᵀJ̃2 (the unprojected rows); damping grows below w0
        pivots_ = A_;
        pivots_.diagonal().array() += 1e-12;
        core::ltdl_factorize(model_, pivots_);
        double log_det = 0;
        for (int i = 0; i < n; ++i) log_det += std::log(pivots_(i, i));
        const double w = std::exp(0.5 * log_det / n);
        const double w0 = settings_.manipulability_threshold;
        k = std::max(1e-12, w < w0 ? settings_.damping * (1 - w / w0) * (1 - w / w0) : 0.0);
      }
      report_.lower_damping = k;
      A_.diagonal().array() += k;
      core::ltdl_factorize(model_, A_);
      y_columns_ = 0;
    }
    // right-hand side b = J̃2ᵀ (ṽ2 − J̃2 x), sparse like A
    dp = v2_.head(m2_).cwiseProduct(row_scale2_.head(m2_));
    dp.noalias() -= J2 * x;
    b_.setZero();
    for (int r = 0; r < m2_; ++r) {
      const int sup = row_support_[r];
      if (sup < 0) {
        b_[-1 - sup] += J2(r, -1 - sup) * dp[r];
        continue;
      }
      for (const int c : link_support_[sup]) b_[c] += J2(r, c) * dp[r];
    }
    const Eigen::MatrixXd& A = A_;
    // unconstrained step u = A⁻¹ b, then the correction that keeps C Δ = 0
    ltdl_half_rhs_ = b_;
    core::ltdl_solve_lt(model_, A, ltdl_half_rhs_);  // L⁻ᵀ b
    const int mc = m1_ + mR_;
    if (mc == 0) {
      y_ = ltdl_half_rhs_.cwiseQuotient(A.diagonal());
      core::ltdl_solve_l(model_, A, y_);
    } else {
      if (Y_.rows() != n || Y_.cols() < mc) {
        Y_.conservativeResize(n, std::max<Eigen::Index>(mc, 2 * Y_.cols()));  // keeps valid columns
      }
      if (Sc_.rows() < mc) Sc_.resize(mc, mc);
      if (t_.size() < mc) t_.resize(mc);
      // with A = Lᵀ D L: Z = L⁻ᵀ Cᵀ (half solves, each staying on its row's root path), then
      // C A⁻¹ Cᵀ = Zᵀ D⁻¹ Z and the correction A⁻¹ Cᵀ λ = L⁻¹ D⁻¹ Z λ. Columns of earlier
      // rounds are still valid.
      for (int r = y_columns_; r < mc; ++r) {
        if (r < m1_) {
          Y_.col(r) = J1s_.row(r).transpose();
        } else {
          Y_.col(r) = SR_.row(r - m1_).transpose();
        }
        core::ltdl_solve_lt(model_, A, Y_.col(r));
      }
      y_columns_ = mc;
      auto Sc = Sc_.topLeftCorner(mc, mc);
      auto Z = Y_.leftCols(mc);
      auto tc = t_.head(mc);
      const auto Dinv = A.diagonal().cwiseInverse();
      // Sc = Zᵀ D⁻¹ Z (+ a tiny ridge: when a range row repeats a drag direction the system is
      // singular but consistent, and the ridge picks the finite solution); tc = C u
      Sc.noalias() = Z.transpose() * Dinv.asDiagonal() * Z;
      tc.noalias() = Z.transpose() * (Dinv.asDiagonal() * ltdl_half_rhs_);
      Sc.diagonal().array() += 1e-12 * std::max(1.0, Sc.diagonal().maxCoeff());
      if (cholesky_in_place(Sc)) {
        cholesky_solve(Sc, tc);
      } else {
        tc.setZero();  // cannot happen for a positive ridge; keep the unconstrained step bounded
      }
      // y = u − L⁻¹ D⁻¹ Z λ = L⁻¹ D⁻¹ (L⁻ᵀ b − Z λ)
      y_ = ltdl_half_rhs_ - Z * tc;
      y_.array() *= Dinv.array();
      core::ltdl_solve_l(model_, A, y_);
    }
    report_.lower_solution_norm = y_.norm();
    report_.lower_rhs_norm = dp.norm();
    x += y_;
    x_lower_ = y_;
  } else {
    x_lower_.setZero();
  }
  qdot_ = x.cwiseProduct(col_scale_);
}

void Solver::fill_report(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q) {
  report_.tasks.resize(problem.entries().size());
  for (size_t k = 0; k < problem.entries().size(); ++k) {
    const auto& e = problem.entries()[k];
    TaskReport& r = report_.tasks[k];
    r.id = e.id;
    r.priority = e.priority;
    TaskError err;
    if (const auto* d = std::get_if<DragTask>(&e.task)) {
      r.kind = "drag";
      r.index = d->link;
      err = link_task_error(data, d->link, d->p_LinkPoint, d->mode, d->target_W, d->target_R_W);
    } else if (const auto* p = std::get_if<PinTask>(&e.task)) {
      r.kind = "pin";
      r.index = p->link;
      err = link_task_error(data, p->link, p->p_LinkPoint, p->mode, p->target_W, p->target_R_W);
    } else if (const auto* j = std::get_if<JointReferenceTask>(&e.task)) {
      r.kind = "reference";
      r.index = j->joint;
      err = reference_task_error(model_, q, *j);
    }
    r.position_error = err.position;
    r.orientation_error = err.orientation;
    r.satisfied = err.position <= kSatisfiedPosition && err.orientation <= kSatisfiedOrientation;
  }
  report_.limit_violation = max_range_violation(model_, q);
}

}  // namespace ik
