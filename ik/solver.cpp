#include "ik/solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "ik/settings_checks.hpp"

namespace ik {

namespace {

double gain_or(double g, double fallback) { return g >= 0 ? g : fallback; }

}  // namespace

int add_drag(LinkTask drag, const SolverSettings& s, Problem& problem) {
  if (!s.hard_pins) return problem.add(Task(drag), kTop);
  drag.weight = kHardPinDragWeight;
  return problem.add(Task(drag), kLower);
}

std::string validate(const SolverSettings& s) {
  if (!positive_finite(s.dt)) return "dt must be a finite number > 0";
  if (s.iterations < kMinIterations || s.iterations > kMaxIterations) {
    return "iterations must be in [" + std::to_string(kMinIterations) + ", " +
           std::to_string(kMaxIterations) + "]";
  }
  if (!std::isfinite(s.damping) || s.damping < 0) return "damping must be finite and >= 0";
  if (!std::isfinite(s.top_damping) || s.top_damping < 0)
    return "top_damping must be finite and >= 0";
  if (!std::isfinite(s.top_singular_value) || s.top_singular_value < 0)
    return "top_singular_value must be finite and >= 0";
  if (!positive_finite(s.manipulability_threshold)) return "manipulability_threshold must be > 0";
  for (const auto& [name, g] : {std::pair{"drag_gain", s.drag_gain},
                                {"pin_gain", s.pin_gain},
                                {"reference_gain", s.reference_gain},
                                {"limit_gain", s.limit_gain},
                                {"range_gain", s.range_gain},
                                {"range_damping", s.range_damping}}) {
    if (!std::isfinite(g) || g < 0) return std::string(name) + " must be finite and >= 0";
  }
  if (!positive_finite(s.max_position_error)) return "max_position_error must be > 0";
  if (!positive_finite(s.max_orientation_error)) return "max_orientation_error must be > 0";
  if (!std::isfinite(s.limit_margin) || s.limit_margin < 0) return "limit_margin must be >= 0";
  if (!positive_finite(s.max_joint_step)) return "max_joint_step must be > 0";
  return {};
}

Solver::Solver(const core::Model& model, const SolverSettings& settings)
    : model_(model), settings_(settings), ws_(model) {}

std::string Solver::check_problem(const Problem& problem, const Eigen::VectorXd& q) const {
  const core::Model& m = model_;
  if (q.size() != m.nq || !q.allFinite())
    return "configuration has the wrong size or is not finite";
  const std::string settings_error = validate(settings_);
  if (!settings_error.empty()) return "settings: " + settings_error;
  auto finite_gain = [](double g) { return std::isfinite(g); };
  for (const auto& e : problem.entries()) {
    // the message is only built for a task that breaks a rule: this check runs every step
    const auto who = [&] { return "task " + std::to_string(e.id); };
    std::string err;
    if (const auto* t = std::get_if<LinkTask>(&e.task)) {
      const auto kind = [&] { return to_string(t->role); };
      if (t->link < 1 || t->link >= m.njoints) {
        err = who() + " (" + kind() + "): link index out of range";
      } else if (!t->target_W.allFinite() || !t->p_LinkPoint.allFinite() ||
                 !t->velocity_W.allFinite() || !t->angular_velocity_W.allFinite()) {
        err =
            who() + " (" + kind() + ", link '" + m.link_name[t->link] + "'): target is not finite";
      } else if (!t->target_R_W.coeffs().allFinite() ||
                 std::abs(t->target_R_W.norm() - 1.0) > 1e-6) {
        err = who() + " (" + kind() + ", link '" + m.link_name[t->link] +
              "'): rotation is not a unit quaternion";
      } else if (!finite_gain(t->gain) || !std::isfinite(t->weight) || t->weight < 0) {
        err = who() + " (" + kind() + "): gain and weight must be finite, weight >= 0";
      }
    }
    if (const auto* r = std::get_if<JointReferenceTask>(&e.task)) {
      if (r->joint < 1 || r->joint >= m.njoints) {
        err = who() + " (reference): joint index out of range";
      } else if (!std::isfinite(r->q_ref) || !std::isfinite(r->velocity_ref) ||
                 !r->R_ref.coeffs().allFinite() || !r->angular_velocity_ref.allFinite() ||
                 !finite_gain(r->gain) || !std::isfinite(r->weight) || r->weight < 0) {
        err = who() + " (reference, joint '" + m.joint_name[r->joint] + "'): values are not finite";
      }
    }
    if (!err.empty()) return err;
  }
  for (const int joint : problem.locked_joints) {
    if (joint < 1 || joint >= m.njoints) return "locked joint index out of range";
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
  ws_.reserve(top_task_rows, lower_task_rows);
  for (int j = 0; j < m.nv; ++j) {
    const double w = settings_.use_joint_weights ? m.ik_weight[m.joint_of_v[j]] : 1.0;
    ws_.joint_scale[j] = w > 0 ? 1.0 / std::sqrt(w) : 0.0;  // weight 0 locks the joint
  }
  if (!problem.locked_joints.empty()) {
    for (int j = 0; j < m.nv; ++j) {
      const auto& locked = problem.locked_joints;
      if (std::find(locked.begin(), locked.end(), m.joint_of_v[j]) != locked.end()) {
        ws_.joint_scale[j] = 0.0;
      }
    }
  }

  report_.max_joint_speed = 0;
  report_.step_limited = false;
  for (int it = 0; it < settings_.iterations; ++it) {
    core::compute_joint_jacobians(m, data, q);
    fill_rows(problem, data, q);
    // rows for joints already outside their ranges (Yamane eq. 8.23, §8.3.5)
    ws_.range_blocks.clear();
    std::fill(ws_.range_flagged.begin(), ws_.range_flagged.end(), 0);
    if (problem.enforce_ranges) {
      collect_range_violations(m, q, settings_.limit_gain, settings_.range_gain, ws_.range_blocks,
                               ws_.range_flagged);
    }
    ws_.range_rows = 0;
    append_range_rows(0);
    solve_levels(true);
    // rows for joints this step would carry out of range: stop them at the boundary and solve
    // again, until no further joint would leave its range (an active-set pass per round)
    for (int round = 0; problem.enforce_ranges && round < kMaxRangeRounds; ++round) {
      const size_t before = ws_.range_blocks.size();
      if (collect_range_predictions(m, q, ws_.joint_velocity, h, settings_.limit_margin,
                                    ws_.range_blocks, ws_.range_flagged) == 0) {
        break;
      }
      append_range_rows(before);
      solve_levels(false);
    }
    report_.range_rows = ws_.range_rows;
    limit_step(h);
    report_.max_joint_speed =
        std::max(report_.max_joint_speed, ws_.joint_velocity.cwiseAbs().maxCoeff());
    core::integrate(m, q, ws_.joint_velocity, h, q);
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
  ws_.drag_rows = 0;
  ws_.pin_rows = 0;
  for (const auto& e : problem.entries()) {
    const bool top = e.priority == kTop;
    Eigen::MatrixXd& J = top ? ws_.drag_jacobian : ws_.pin_jacobian;
    Eigen::VectorXd& v = top ? ws_.drag_velocity : ws_.pin_velocity;
    int& row = top ? ws_.drag_rows : ws_.pin_rows;
    double weight = 1.0;
    int rows = 0;
    const LinkTask* link_task = std::get_if<LinkTask>(&e.task);
    const JointReferenceTask* reference = std::get_if<JointReferenceTask>(&e.task);
    if (link_task) {
      rows = task_rows(m, *link_task);
      const double role_gain = link_task->role == kDrag  ? settings_.drag_gain
                               : link_task->role == kPin ? settings_.pin_gain
                                                         : settings_.reference_gain;
      const double K = gain_or(link_task->gain, role_gain);
      fill_link_task(m, data, *link_task, K, clamp, J.middleRows(row, rows), v.segment(row, rows));
      weight = link_task->weight;
    } else if (reference) {
      rows = task_rows(m, *reference);
      const double K =
          gain_or(reference->gain, m.ik_gain[reference->joint].value_or(settings_.reference_gain));
      if (top) {
        fill_reference_task(m, q, *reference, K, clamp, J.middleRows(row, rows),
                            v.segment(row, rows));
      } else {
        // level 3 keeps selection rows as their coordinate (pin_row_support), not dense rows
        reference_task_velocity(m, q, *reference, K, clamp, v.segment(row, rows));
      }
      weight = reference->weight;
    }
    if (!top) {
      ws_.pin_row_scale.segment(row, rows).setConstant(std::sqrt(std::max(0.0, weight)));
      // which coordinates each level-3 row can touch: the link's root path, or one coordinate
      for (int k = 0; k < rows; ++k) {
        ws_.pin_row_support[row + k] =
            link_task ? link_task->link : -1 - (m.idx_v[reference->joint] + k);
      }
    }
    row += rows;
  }
}

namespace {
// largest α in [0, 1] with |a_j + α c_j| <= V for every j (given |a_j| <= V)
double admissible_fraction(const Eigen::VectorXd& a,
                           const Eigen::VectorXd& c,
                           const Eigen::VectorXd& scale,
                           double V) {
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
  if ((ws_.joint_velocity.cwiseAbs().array() <= V).all()) return;
  report_.step_limited = true;
  const Eigen::VectorXd& c = ws_.joint_scale;
  Eigen::VectorXd& a = ws_.x;  // running sum of the levels kept so far
  const Eigen::VectorXd* levels[3] = {&ws_.x_drag, &ws_.x_range, &ws_.x_pin};
  a.setZero();
  for (const Eigen::VectorXd* level : levels) {
    if ((a.cwiseProduct(c).cwiseAbs().array() > V).any()) break;
    a += admissible_fraction(a, *level, c, V) * *level;
  }
  if ((a.cwiseProduct(c).cwiseAbs().array() > V).any()) {
    a *= V / a.cwiseProduct(c).cwiseAbs().maxCoeff();  // cannot happen after level 1
  }
  ws_.joint_velocity = a.cwiseProduct(c);
}

void Solver::append_range_rows(size_t first) {
  // range rows select joint coordinates (Yamane eqs. 8.17–8.20): keep the coordinate index only
  for (size_t k = first; k < ws_.range_blocks.size(); ++k) {
    const RangeRow& r = ws_.range_blocks[k];
    for (int d = 0; d < r.rows; ++d) {
      ws_.range_coordinate[ws_.range_rows] = model_.idx_v[r.joint] + d;
      ws_.range_velocity[ws_.range_rows] = r.desired[d];
      ++ws_.range_rows;
    }
  }
}

void Solver::fill_report(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q) {
  report_.tasks.resize(problem.entries().size());
  for (size_t k = 0; k < problem.entries().size(); ++k) {
    const auto& e = problem.entries()[k];
    TaskReport& r = report_.tasks[k];
    r.id = e.id;
    r.priority = e.priority;
    TaskError err;
    if (const auto* t = std::get_if<LinkTask>(&e.task)) {
      r.kind = to_string(t->role);
      r.index = t->link;
      err = link_task_error(data, *t);
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
