#include "ik/acceleration_solver.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/configuration.hpp"
#include "ik/settings_checks.hpp"

namespace ik {

namespace {

double frequency_or(double gain, double fallback) { return gain >= 0 ? gain : fallback; }

}  // namespace

std::string validate(const AccelerationSettings& s) {
  for (const auto& [name, value] : {std::pair{"drag_frequency", s.drag_frequency},
                                    {"pin_frequency", s.pin_frequency},
                                    {"reference_frequency", s.reference_frequency},
                                    {"range_frequency", s.range_frequency},
                                    {"max_position_error", s.max_position_error},
                                    {"max_orientation_error", s.max_orientation_error},
                                    {"step", s.step},
                                    {"max_joint_acceleration", s.max_joint_acceleration},
                                    {"max_joint_speed", s.max_joint_speed}}) {
    if (!positive_finite(value)) return std::string(name) + " must be a finite number > 0";
  }
  for (const auto& [name, value] : {std::pair{"top_singular_value", s.top_singular_value},
                                    {"top_damping", s.top_damping},
                                    {"range_damping", s.range_damping},
                                    {"damping", s.damping}}) {
    if (!std::isfinite(value) || value < 0) return std::string(name) + " must be finite and >= 0";
  }
  return {};
}

AccelerationSolver::AccelerationSolver(const core::Model& model, const AccelerationSettings& s)
    : model_(model),
      settings_(s),
      n_(std::max(0, model.nv - 6)),
      X_(6, n_),
      col_scale_(Eigen::VectorXd::Ones(n_)),
      J_(6, model.nv),
      vd_(6),
      jdv_(6),
      range_flags_(model.njoints, 0),
      G1_(kMaxDragRows, kMaxDragRows),
      G1inv_(kMaxDragRows, kMaxDragRows),
      eigen1_(kMaxDragRows),
      t1_(kMaxDragRows),
      P1_(kMaxDragRows, n_),
      x_(n_),
      acceleration_(Eigen::VectorXd::Zero(model.nv)),
      torque_(Eigen::VectorXd::Zero(model.nv)) {
  range_rows_.reserve(model.njoints);
}

std::string AccelerationSolver::check(const Problem& problem, const Eigen::VectorXd& q) const {
  const core::Model& m = model_;
  if (m.njoints < 2 || m.joint_type[1] != core::JointType::kFree) {
    return "the acceleration-level solver needs a free root joint";
  }
  if (q.size() != m.nq || !q.allFinite())
    return "configuration has the wrong size or is not finite";
  const std::string settings_error = validate(settings_);
  if (!settings_error.empty()) return "settings: " + settings_error;
  int top = 0;
  for (const Problem::Entry& e : problem.entries()) {
    const std::string who = "task " + std::to_string(e.id);
    if (const auto* t = std::get_if<LinkTask>(&e.task)) {
      if (t->link < 1 || t->link >= m.njoints) return who + ": link index out of range";
      if (!t->target_W.allFinite() || !t->p_LinkPoint.allFinite() || !t->velocity_W.allFinite() ||
          !t->angular_velocity_W.allFinite() || !t->target_R_W.coeffs().allFinite() ||
          !std::isfinite(t->gain) || !std::isfinite(t->weight) || t->weight < 0) {
        return who + ": target, gain and weight must be finite, weight >= 0";
      }
      if (e.priority == kTop) top += task_rows(m, *t);
    } else if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
      if (r->joint < 2 || r->joint >= m.njoints) {
        return who + ": joint index out of range (the root has no reference at this level)";
      }
      if (!std::isfinite(r->q_ref) || !r->R_ref.coeffs().allFinite() || !std::isfinite(r->gain) ||
          !std::isfinite(r->weight) || r->weight < 0) {
        return who + ": values are not finite";
      }
    }
  }
  if (top > kMaxDragRows) {
    return "level 1 holds " + std::to_string(top) + " rows (rule: at most " +
           std::to_string(kMaxDragRows) + " at acceleration level)";
  }
  return {};
}

const AccelerationReport& AccelerationSolver::solve(const Problem& problem,
                                                    const core::Data& data,
                                                    const Eigen::VectorXd& q,
                                                    const Eigen::VectorXd& v,
                                                    const Eigen::VectorXd& bias,
                                                    const Eigen::VectorXd& contact) {
  report_ = AccelerationReport{};
  report_.message = check(problem, q);
  if (!report_.message.empty()) {
    report_.status = AccelerationReport::Status::kRejected;
    return report_;
  }
  for (int j = 0; j < n_; ++j) {
    const double w = settings_.use_joint_weights ? model_.ik_weight[model_.joint_of_v[6 + j]] : 1;
    col_scale_[j] = w > 0 ? 1.0 / std::sqrt(w) : 0.0;  // weight 0 locks the joint
  }
  split_root(data, bias, contact);
  fill_rows(problem, data, q, v);
  solve_levels();
  acceleration_.tail(n_) = x_.cwiseProduct(col_scale_);
  if (!bound_joint_accelerations(v)) {
    report_.status = AccelerationReport::Status::kRejected;
    report_.message = "the joint accelerations are not finite";
    return report_;
  }
  finish(data, bias, contact);
  return report_;
}

// Cuts q̈ to the bounds of the settings; false when it is not finite.
bool AccelerationSolver::bound_joint_accelerations(const Eigen::VectorXd& v) {
  auto qdd = acceleration_.tail(n_);
  if (!qdd.allFinite()) return false;
  if (n_ == 0) return true;
  const double largest = qdd.cwiseAbs().maxCoeff();
  if (largest > settings_.max_joint_acceleration) {
    qdd *= settings_.max_joint_acceleration / largest;
    report_.bounded = true;
  }
  const double h = settings_.step, vmax = settings_.max_joint_speed;
  for (int j = 0; j < n_; ++j) {
    const double vj = v[6 + j];
    const double cut = std::clamp(qdd[j], (-vmax - vj) / h, (vmax - vj) / h);
    if (cut != qdd[j]) {
      qdd[j] = cut;
      report_.bounded = true;
    }
  }
  hold_at_ranges(v);
  return true;
}

// A joint already beyond its range does not go further out, whatever the drag asks: the part of
// its velocity after the step that points out of the range (against the range row's desired
// velocity d, which points back in) is removed. The drag then lags instead of winding the joint
// around (a drag out of reach would otherwise spin the limbs at the speed bound).
void AccelerationSolver::hold_at_ranges(const Eigen::VectorXd& v) {
  const double h = settings_.step;
  auto qdd = acceleration_.tail(n_);
  for (int i = 0; i < range_violations_; ++i) {
    const RangeRow& rr = range_rows_[i];
    const int c = model_.idx_v[rr.joint] - 6;
    if (c < 0) continue;
    const auto d = rr.desired.head(rr.rows);
    const double dd = d.squaredNorm();
    if (!(dd > 0)) continue;
    const double outward = -d.dot(v.segment(6 + c, rr.rows) + h * qdd.segment(c, rr.rows));
    if (outward <= 0) continue;
    qdd.segment(c, rr.rows) += (outward / (h * dd)) * d;
    report_.bounded = true;
  }
}

void AccelerationSolver::split_root(const core::Data& data,
                                    const Eigen::VectorXd& bias,
                                    const Eigen::VectorXd& Q) {
  // X = H_bb⁻¹ H_bq and y = H_bb⁻¹ (Q_b − b_b): the root rows of the EOM (digest §2.8)
  Hbb_ = data.M.topLeftCorner<6, 6>();
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(Hbb_);
  X_ = data.M.topRightCorner(6, n_);
  if (n_ > 0) llt.solveInPlace(X_);  // a body without joints has no coupling to solve
  y_ = Q.head<6>() - bias.head<6>();
  llt.solveInPlace(y_);
}

void AccelerationSolver::reserve_rows(Eigen::MatrixXd& A, Eigen::VectorXd& b, int rows) {
  if (A.rows() < rows) {
    A.conservativeResize(std::max<Eigen::Index>(rows, 2 * A.rows()), n_);
    b.conservativeResize(A.rows());
  }
}

// A joint reference's rows: its Jacobian selects the joint's own coordinates (J_b = 0, J̇v = 0),
// so Γ is that selection and each row has one entry: c_j q̈_j = 2ω (q̇ᵈ_j − q̇_j).
void AccelerationSolver::add_selection_rows(
    bool top,
    int coordinate,
    int rows,
    const Eigen::Ref<const Eigen::VectorXd>& velocity_desired,
    double frequency,
    double weight,
    const Eigen::VectorXd& v) {
  Eigen::MatrixXd& A = top ? A1_ : A3_;
  Eigen::VectorXd& b = top ? b1_ : b3_;
  int& m = top ? m1_ : m3_;
  reserve_rows(A, b, m + rows);
  const double row_scale = top ? 1.0 : std::sqrt(weight);
  A.middleRows(m, rows).setZero();
  for (int d = 0; d < rows; ++d) {
    const int c = coordinate + d;
    A(m + d, c) = row_scale * col_scale_[c];
    b[m + d] = row_scale * 2.0 * frequency * (velocity_desired[d] - v[6 + c]);
  }
  m += rows;
}

// One task's rows: J (over all nv coordinates), the velocity-level desired velocity ṙᵈ (at gain
// K_p / K_v = ω / 2) and J̇v, turned into rows Γ q̈ = 2ω (ṙᵈ − J v) − J̇v − J_b y on a level.
void AccelerationSolver::add_row_block(bool top,
                                       const Eigen::Ref<const Eigen::MatrixXd>& J,
                                       const Eigen::Ref<const Eigen::VectorXd>& velocity_desired,
                                       const Eigen::Ref<const Eigen::VectorXd>& jdot_v,
                                       double frequency,
                                       double weight,
                                       const Eigen::VectorXd& v) {
  const int rows = static_cast<int>(J.rows());
  Eigen::MatrixXd& A = top ? A1_ : A3_;
  Eigen::VectorXd& b = top ? b1_ : b3_;
  int& m = top ? m1_ : m3_;
  reserve_rows(A, b, m + rows);
  const double row_scale = top ? 1.0 : std::sqrt(weight);
  auto Ablock = A.middleRows(m, rows);
  // Γ = J_q − J_b X, columns scaled by the joint weights
  Ablock.noalias() = J.rightCols(n_);
  Ablock.noalias() -= J.leftCols<6>() * X_;
  Ablock = (Ablock.array().rowwise() * col_scale_.transpose().array()) * row_scale;
  auto bblock = b.segment(m, rows);
  bblock.noalias() = 2.0 * frequency * velocity_desired;
  bblock.noalias() -= (2.0 * frequency * J) * v;
  bblock -= jdot_v;
  bblock.noalias() -= J.leftCols<6>() * y_;
  bblock *= row_scale;
  m += rows;
}

void AccelerationSolver::fill_rows(const Problem& problem,
                                   const core::Data& data,
                                   const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& v) {
  const core::Model& m = model_;
  m1_ = m2_ = m3_ = 0;
  for (const Problem::Entry& e : problem.entries()) {
    const bool top = e.priority == kTop;
    if (const auto* t = std::get_if<LinkTask>(&e.task)) {
      const int rows = task_rows(m, *t);
      const double w = frequency_or(
          t->gain, t->role == kDrag ? settings_.drag_frequency : settings_.pin_frequency);
      const ErrorClamp clamp{settings_.max_position_error, settings_.max_orientation_error};
      fill_link_task(m, data, *t, 0.5 * w, clamp, J_.topRows(rows), vd_.head(rows));
      const core::PointMotion jdv = core::point_jdot_v(m, data, t->link, t->p_LinkPoint);
      int r = 0;
      if (t->mode != TaskMode::kPosition) {
        jdv_.segment<3>(r) = jdv.angular;
        r += 3;
      }
      if (t->mode != TaskMode::kOrientation) jdv_.segment<3>(r) = jdv.linear;
      add_row_block(top, J_.topRows(rows), vd_.head(rows), jdv_.head(rows), w, t->weight, v);
    } else if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
      const int rows = task_rows(m, *r);
      const double w = frequency_or(r->gain, settings_.reference_frequency);
      const ErrorClamp clamp{settings_.max_position_error, settings_.max_orientation_error};
      fill_reference_task(m, q, *r, 0.5 * w, clamp, J_.topRows(rows), vd_.head(rows));
      add_selection_rows(top, m.idx_v[r->joint] - 6, rows, vd_.head(rows), w, r->weight, v);
    }
  }
  // level 2: joints beyond their ranges are pulled back, joints that would leave them within
  // the range rows' time constant are stopped at the boundary (ik/limits.hpp, velocity laws)
  range_rows_.clear();
  range_violations_ = 0;
  std::fill(range_flags_.begin(), range_flags_.end(), 0);
  if (!problem.enforce_ranges) return;
  const double w = settings_.range_frequency;
  collect_range_violations(m, q, 0.5 * w, 0.5 * w, range_rows_, range_flags_);
  range_violations_ = static_cast<int>(range_rows_.size());
  collect_range_predictions(m, q, v, 0.5 / w, 1e-3, range_rows_, range_flags_);
  int rows = 0;
  for (const RangeRow& rr : range_rows_) rows += rr.rows;
  if (A2_.rows() < rows) {
    A2_.resize(std::max(rows, 2 * static_cast<int>(A2_.rows())), n_);
    b2_.resize(A2_.rows());
  }
  for (const RangeRow& rr : range_rows_) {
    for (int d = 0; d < rr.rows; ++d) {
      const int c = m.idx_v[rr.joint] + d - 6;  // joint coordinate (joints below the root)
      if (c < 0) continue;
      A2_.row(m2_).setZero();
      A2_(m2_, c) = col_scale_[c];
      b2_[m2_] = 2.0 * w * (rr.desired[d] - v[6 + c]);
      ++m2_;
    }
  }
}

// Applies the null-space projector of levels 1 and 2 to the rows of A: out = A N, with N kept
// in factored form, N = E − A1ᵀ P1 − S2ᵀ P2 (P1 = G1⁺ A1, P2 = G2⁻¹ S2), which costs
// 2 rows · n · (m1 + m2) instead of rows · n² for a dense N.
void AccelerationSolver::project(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                 Eigen::Ref<Eigen::MatrixXd> out,
                                 bool with_level2) {
  const Eigen::Index rows = A.rows();
  out = A;
  const Eigen::Index cols = std::max({n_, m1_, m2_});
  if (C_.rows() < rows || C_.cols() < cols) C_.resize(std::max(rows, C_.rows()), cols);
  if (m1_ > 0) {
    auto C = C_.topLeftCorner(rows, m1_);
    C.noalias() = A * A1_.topRows(m1_).transpose();
    out.noalias() -= C * P1_.topRows(m1_);
  }
  if (with_level2 && m2_ > 0) {
    auto C = C_.topLeftCorner(rows, m2_);
    C.noalias() = A * S2_.topRows(m2_).transpose();
    out.noalias() -= C * P2_.topRows(m2_);
  }
}

void AccelerationSolver::solve_levels() {
  report_.top_rows = m1_;
  report_.range_rows = m2_;
  report_.lower_rows = m3_;
  x_.setZero();
  // level 1, the drag: x = A1ᵀ G⁺ b1 with G = A1 A1ᵀ, damped only where a singular value of A1
  // falls below s0 (λ² = k (1 − σ²/s0²)), and N = E − A1ᵀ G⁺ A1
  if (m1_ > 0) {
    const auto A1 = A1_.topRows(m1_);
    G1_.resize(m1_, m1_);
    G1_.noalias() = A1 * A1.transpose();
    eigen1_.compute(G1_);
    const double s02 = settings_.top_singular_value * settings_.top_singular_value;
    const double tol = 1e-12 * std::max(1.0, eigen1_.eigenvalues().maxCoeff());
    t1_.resize(m1_);
    for (int k = 0; k < m1_; ++k) {
      const double sigma2 = std::max(0.0, eigen1_.eigenvalues()[k]);
      const double lambda2 = sigma2 < s02 ? settings_.top_damping * (1.0 - sigma2 / s02) : 0.0;
      report_.top_damped = report_.top_damped || lambda2 > 0;
      if (sigma2 > tol) ++report_.top_rank;
      t1_[k] = sigma2 + lambda2 > tol ? 1.0 / (sigma2 + lambda2) : 0.0;
    }
    G1inv_.resize(m1_, m1_);
    G1inv_.noalias() =
        eigen1_.eigenvectors() * t1_.asDiagonal() * eigen1_.eigenvectors().transpose();
    t1_.noalias() = G1inv_ * b1_.head(m1_);
    x_.noalias() = A1.transpose() * t1_;
    P1_.topRows(m1_).noalias() = G1inv_ * A1;
  }
  // level 2, the ranges: S2 = A2 N, x += S2ᵀ (S2 S2ᵀ + k E)⁻¹ (b2 − A2 x), N −= S2ᵀ G2⁻¹ S2
  if (m2_ > 0) {
    if (S2_.rows() < m2_ || S2_.cols() != n_) S2_.resize(std::max<int>(m2_, S2_.rows()), n_);
    if (G2_.rows() < m2_) G2_.resize(m2_, m2_);
    if (P2_.rows() < m2_ || P2_.cols() != n_) P2_.resize(std::max<int>(m2_, P2_.rows()), n_);
    if (t2_.size() < m2_) t2_.resize(m2_);
    auto S2 = S2_.topRows(m2_);
    project(A2_.topRows(m2_), S2, false);
    auto G2 = G2_.topLeftCorner(m2_, m2_);
    G2.noalias() = S2 * S2.transpose();
    G2.diagonal().array() += std::max(settings_.range_damping, 1e-12);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(G2);
    auto t2 = t2_.head(m2_);
    t2 = b2_.head(m2_);
    t2.noalias() -= A2_.topRows(m2_) * x_;
    llt.solveInPlace(t2);
    x_.noalias() += S2.transpose() * t2;
    auto P = P2_.topRows(m2_);
    P = S2;
    llt.solveInPlace(P);
  }
  // level 3, pins and references: the SR inverse of S3 = A3 N on the residual (Yamane eq. 8.16)
  if (m3_ > 0) {
    if (S3_.rows() < m3_ || S3_.cols() != n_) S3_.resize(std::max<int>(m3_, S3_.rows()), n_);
    if (r_.size() < m3_) r_.resize(m3_);
    if (y3_.size() != n_) y3_.resize(n_);
    auto S3 = S3_.topRows(m3_);
    project(A3_.topRows(m3_), S3, true);
    auto r = r_.head(m3_);
    r = b3_.head(m3_);
    r.noalias() -= A3_.topRows(m3_) * x_;
    sr_.solve(S3, r, settings_.damping, DampingSchedule::kConstant, 1.0, y3_);
    x_ += y3_;
  }
}

void AccelerationSolver::finish(const core::Data& data,
                                const Eigen::VectorXd& bias,
                                const Eigen::VectorXd& Q) {
  // θ̈_b = y − X q̈ (the root rows), q̈ = diag(c) x as bounded; τ from the joint rows of the EOM
  const auto qdd = acceleration_.tail(n_);
  acceleration_.head<6>() = y_;
  acceleration_.head<6>().noalias() -= X_ * qdd;
  torque_.head<6>().setZero();
  torque_.tail(n_) = bias.tail(n_) - Q.tail(n_);
  torque_.tail(n_).noalias() += data.M.bottomRows(n_) * acceleration_;
  Eigen::Matrix<double, 6, 1> root = bias.head<6>() - Q.head<6>();
  root.noalias() += data.M.topRows<6>() * acceleration_;
  report_.root_residual = root.norm();
}

}  // namespace ik
