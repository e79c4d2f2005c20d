#include "ik/solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>

#include "core/configuration.hpp"
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
                                {"range_gain", s.range_gain}, {"range_weight", s.range_weight}}) {
    if (!std::isfinite(g) || g < 0) return std::string(name) + " must be finite and >= 0";
  }
  if (!positive_finite(s.max_position_error)) return "max_position_error must be > 0";
  if (!positive_finite(s.max_orientation_error)) return "max_orientation_error must be > 0";
  if (!std::isfinite(s.limit_margin) || s.limit_margin < 0) return "limit_margin must be >= 0";
  return {};
}

Solver::Solver(const core::Model& model, const SolverSettings& settings)
    : model_(model),
      settings_(settings),
      col_scale_(Eigen::VectorXd::Ones(model.nv)),
      x0_(Eigen::VectorXd::Zero(model.nv)),
      y_(Eigen::VectorXd::Zero(model.nv)),
      qdot_(Eigen::VectorXd::Zero(model.nv)),
      scaled_(Eigen::VectorXd::Zero(model.nv)),
      point_(model.nv),
      range_flags_(model.njoints, 0) {
  int range_capacity = 0;
  for (int i = 1; i < model.njoints; ++i) range_capacity += range_block_rows(model, i);
  range_rows_.reserve(model.njoints);
  // the range rows can land on either level
  J1_.resize(range_capacity, model.nv);
  J2_.resize(range_capacity, model.nv);
  v1_.resize(range_capacity);
  v2_.resize(range_capacity);
  row_scale2_.resize(range_capacity);
}

const Report& Solver::step(const Problem& problem, core::Data& data, Eigen::VectorXd& q) {
  const auto t0 = std::chrono::steady_clock::now();
  const core::Model& m = model_;
  const double h = settings_.dt / settings_.iterations;

  // size the workspace for this problem (only grows)
  int top_task_rows = 0, lower_task_rows = 0;
  for (const auto& e : problem.entries()) {
    const int r = std::visit([&](const auto& t) { return task_rows(m, t); }, e.task);
    (e.priority == kTop ? top_task_rows : lower_task_rows) += r;
  }
  int range_capacity = 0;
  for (int i = 1; i < m.njoints; ++i) range_capacity += range_block_rows(m, i);
  const int cap1 = top_task_rows + range_capacity, cap2 = lower_task_rows + range_capacity;
  if (J1_.rows() < cap1) {
    J1_.resize(cap1, m.nv);
    v1_.resize(cap1);
  }
  if (J2_.rows() < cap2) {
    J2_.resize(cap2, m.nv);
    v2_.resize(cap2);
    row_scale2_.resize(cap2);
  }
  for (int j = 0; j < m.nv; ++j) {
    const double w = settings_.use_joint_weights ? m.ik_weight[m.joint_of_v[j]] : 1.0;
    col_scale_[j] = w > 0 ? 1.0 / std::sqrt(w) : 0.0;  // weight 0 locks the joint
  }

  report_.max_joint_speed = 0;
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
    append_range_rows(0);
    solve_levels();
    // rows for joints this step would carry out of range: stop them at the boundary, solve again
    if (problem.enforce_ranges) {
      const size_t before = range_rows_.size();
      if (collect_range_predictions(m, q, qdot_, h, settings_.limit_margin, range_rows_,
                                    range_flags_) > 0) {
        append_range_rows(before);
        solve_levels();
      }
    }
    report_.range_rows = 0;
    for (const RangeRow& r : range_rows_) report_.range_rows += r.rows;
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
    if (!top) row_scale2_.segment(row, rows).setConstant(std::sqrt(std::max(0.0, weight)));
    row += rows;
  }
}

void Solver::append_range_rows(size_t first) {
  const core::Model& m = model_;
  for (size_t k = first; k < range_rows_.size(); ++k) {
    const RangeRow& r = range_rows_[k];
    const int iv = m.idx_v[r.joint];
    Eigen::MatrixXd& J = J2_;
    int& row = m2_;
    J.middleRows(row, r.rows).setZero();
    for (int d = 0; d < r.rows; ++d) {
      J(row + d, iv + d) = 1.0;  // selection rows (Yamane eqs. 8.17–8.20)
      v2_[row + d] = r.desired[d];
      row_scale2_[row + d] = std::sqrt(settings_.range_weight);
    }
    row += r.rows;
  }
}

void Solver::solve_levels() {
  const int n = model_.nv;
  const auto col = col_scale_.transpose().array();
  // top level: x0 = J̃1ᵀ G⁻¹ v1 with J̃1 = J1 diag(col), G = J̃1 J̃1ᵀ
  report_.top_rows = m1_;
  report_.top_damped = false;
  report_.top_rank = 0;
  if (m1_ > 0) {
    if (P_.rows() < m1_ || P_.cols() != n) P_.resize(std::max<Eigen::Index>(m1_, P_.rows()), n);
    if (G_.rows() < m1_) G_.resize(m1_, m1_);
    if (t1_.size() < m1_) t1_.resize(m1_);
    if (J1s_.rows() < m1_ || J1s_.cols() != n) J1s_.resize(std::max<Eigen::Index>(m1_, J1s_.rows()), n);
    if (E_.rows() < m1_) E_.resize(m1_, m1_);
    auto J1 = J1s_.topRows(m1_);
    J1 = J1_.topRows(m1_).array().rowwise() * col;
    auto G = G_.topLeftCorner(m1_, m1_);
    G.setZero();
    G.selfadjointView<Eigen::Lower>().rankUpdate(J1);
    auto P = P_.topRows(m1_);
    auto t1 = t1_.head(m1_);
    // exact pseudoinverse while every singular value of J̃1 exceeds the threshold
    const double s0 = settings_.top_singular_value;
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(G);
    bool well_conditioned = llt.info() == Eigen::Success;
    if (well_conditioned) {
      // σ_min² ≥ 1 / trace(G⁻¹) = 1 / |L⁻¹|²_F: a cheap lower bound on the smallest singular value
      auto Linv = E_.topLeftCorner(m1_, m1_);
      Linv.setIdentity();
      llt.matrixL().solveInPlace(Linv);
      well_conditioned = Linv.squaredNorm() * s0 * s0 < 1.0;
    }
    if (well_conditioned) {
      P = J1;
      llt.solveInPlace(P);
      t1 = v1_.head(m1_);
      llt.solveInPlace(t1);
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
      const Eigen::MatrixXd Ginv = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
      P.noalias() = Ginv * J1;
      t1.noalias() = Ginv * v1_.head(m1_);
    }
    x0_.noalias() = J1.transpose() * t1;
  } else {
    x0_.setZero();
  }

  // lower level: y = S* (v2 − J̃2 x0), S = J̃2 W = J̃2 − (J̃2 J̃1ᵀ) P, rows scaled by √weight
  report_.lower_rows = m2_;
  Eigen::VectorXd& x = scaled_;
  x = x0_;
  if (m2_ > 0) {
    if (J2s_.rows() < m2_ || J2s_.cols() != n) J2s_.resize(std::max<Eigen::Index>(m2_, J2s_.rows()), n);
    auto J2 = J2s_.topRows(m2_);
    J2 = (J2_.topRows(m2_).array().rowwise() * col).colwise() * row_scale2_.head(m2_).array();
    if (dp_.size() < m2_) dp_.resize(m2_);
    auto dp = dp_.head(m2_);
    dp = v2_.head(m2_).cwiseProduct(row_scale2_.head(m2_));
    dp.noalias() -= J2 * x0_;
    if (S_.rows() < m2_ || S_.cols() != n) S_.resize(std::max<Eigen::Index>(m2_, S_.rows()), n);
    auto S = S_.topRows(m2_);
    S = J2;
    if (m1_ > 0) {
      if (JJ_.rows() < m2_ || JJ_.cols() < m1_) JJ_.resize(std::max<Eigen::Index>(m2_, JJ_.rows()), std::max<Eigen::Index>(m1_, JJ_.cols()));
      auto JJ = JJ_.topLeftCorner(m2_, m1_);
      JJ.noalias() = J2 * J1s_.topRows(m1_).transpose();
      S.noalias() -= JJ * P_.topRows(m1_);
    }
    const SrInverse::Result r = sr_.solve(S, dp, settings_.damping, settings_.damping_schedule,
                                          settings_.manipulability_threshold, y_);
    report_.lower_damping = r.damping;
    if (m1_ > 0) {
      // W y = y − J̃1ᵀ (P y): keeps the top level untouched despite rounding
      t1_.head(m1_).noalias() = P_.topRows(m1_) * y_;
      y_.noalias() -= J1s_.topRows(m1_).transpose() * t1_.head(m1_);
    }
    x += y_;
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
