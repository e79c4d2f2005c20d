#include "ik/pin_hold.hpp"

#include <algorithm>

#include "core/kinematics.hpp"
#include "ik/limits.hpp"

namespace ik {

namespace {

bool is_hard_pin(const Problem::Entry& e) {
  const auto* t = std::get_if<LinkTask>(&e.task);
  return t && t->role == kPin && e.priority == kTop;
}

}  // namespace

double PinHold::hard_pin_error(const Problem& problem, const core::Data& data) {
  double worst = 0;
  for (const Problem::Entry& e : problem.entries()) {
    if (!is_hard_pin(e)) continue;
    const TaskError err = link_task_error(data, std::get<LinkTask>(e.task));
    worst = std::max({worst, err.position, err.orientation});
  }
  return worst;
}

void PinHold::build_correction(const Problem& problem, double gain) {
  // the hard pins alone, on level 1: the least (joint-weighted) change of pose that puts them
  // back. Nothing is held on level 3: a dragged link held there against knees that are almost
  // straight asks the null space for a singular motion.
  correction_.clear();
  correction_.enforce_ranges = false;  // ranges are kept by locking joints (hold)
  for (const Problem::Entry& e : problem.entries()) {
    if (!is_hard_pin(e)) continue;
    LinkTask c = std::get<LinkTask>(e.task);
    c.velocity_W.setZero();  // a correction is positional: the targets of this instant
    c.angular_velocity_W.setZero();
    c.gain = gain;
    correction_.add(Task(c), kTop);
  }
}

bool PinHold::correct_once(const Problem& problem,
                           core::Data& data,
                           Eigen::VectorXd& q,
                           double gain) {
  // Ranges rank above the pins in a correction: a joint the correction would carry out of its
  // range is locked and the correction solved again without it (the clamping loop of
  // Baerlocher and Boulic). Range rows on a level below the pins would fight them where the
  // pins alone fix that joint (both knees straight close a loop through the root).
  const core::Model& m = solver_.model();
  build_correction(problem, gain);
  range_flags_before_.assign(m.njoints, 0);
  range_rows_.clear();
  if (problem.enforce_ranges) {
    collect_range_violations(m, start_q_, 0, 0, range_rows_, range_flags_before_);
  }
  for (int round = 0; round <= kMaxLockRounds; ++round) {
    const Report& r = solver_.step(correction_, data, q);
    if (r.status != Report::Status::kOk) return false;
    if (!problem.enforce_ranges) return true;
    range_flags_.assign(m.njoints, 0);
    range_rows_.clear();
    collect_range_violations(m, q, 0, 0, range_rows_, range_flags_);
    bool locked_more = false;
    for (int j = 1; j < m.njoints; ++j) {
      // a joint out of range after the correction (one out before it stays where it was)
      if ((range_flags_[j] || range_flags_before_[j]) &&
          std::find(correction_.locked_joints.begin(), correction_.locked_joints.end(), j) ==
              correction_.locked_joints.end()) {
        correction_.locked_joints.push_back(j);
        locked_more = true;
      }
    }
    if (!locked_more) return true;
    q = start_q_;
    core::forward_kinematics(m, data, q);
  }
  return false;  // still leaving a range after every round: no correction
}

const PinHoldReport& PinHold::hold(const SolverSettings& settings,
                                   const Problem& problem,
                                   core::Data& data,
                                   Eigen::VectorXd& q,
                                   double tolerance,
                                   int max_corrections) {
  report_ = {};
  report_.error_before = hard_pin_error(problem, data);
  report_.error_after = report_.error_before;
  if (report_.error_after <= tolerance) return report_;
  // K h = 1 on each of the solver's sub-steps of dt / iterations (digest §2.3): the whole error
  solver_.set_settings(settings);
  const double gain = settings.iterations / settings.dt;
  const core::Model& m = solver_.model();
  while (report_.corrections < max_corrections && report_.error_after > tolerance) {
    start_q_ = q;
    const bool done = correct_once(problem, data, q, gain);
    const double error = done ? hard_pin_error(problem, data) : report_.error_after;
    if (!done || error >= report_.error_after) {
      // no better: the pose stays as it was (pins that cannot all be met, or only by leaving
      // a range)
      q = start_q_;
      core::forward_kinematics(m, data, q);
      break;
    }
    ++report_.corrections;
    const double previous = report_.error_after;
    report_.error_after = error;
    if (error > 0.5 * previous) break;  // no longer converging: Newton would halve it
  }
  return report_;
}

}  // namespace ik
