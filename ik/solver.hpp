// The pin-and-drag IK solver (Yamane §8.2.4, digest §2.2), with three priority levels, each
// solved in the null space of the levels above it:
//
// 1. The drag: rows J1 θ̇ = v1 of the tasks added with kTop, solved exactly with the
//    joint-weighted pseudoinverse; damped only along directions where J1 loses rank (fixed
//    root, stretched limb).
// 2. Joint ranges: rows for joints at or beyond their ranges (ik/limits.hpp). The book puts
//    them with the pins; on a level of their own above the pins, a pinned link gives way before
//    a joint leaves its range, and a weight never has to outshout the pins.
// 3. Pins and references: rows J2 θ̇ = v2 of the tasks added with kLower, solved with the SR
//    inverse (eq. 8.7): y = (J2 W)* (v2 − J2 θ̇0), θ̇ = θ̇0 + W y (eqs. 8.14–8.16), with the
//    projector W of levels 1 and 2 applied implicitly (never an N×N matrix).
//
// Joint velocities are integrated on the configuration manifold (core::integrate).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/data.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"
#include "ik/limits.hpp"
#include "ik/problem.hpp"
#include "ik/solver_workspace.hpp"
#include "ik/sr_inverse.hpp"

namespace ik {

// Default tuning (named so the accuracy-versus-time report can sweep them). Gains are in 1/s;
// with explicit integration the error shrinks by (1 − K h) per step, so K h ≤ 1 (digest §2.3).
constexpr double kDefaultTimeStep = 1.0 / 60.0;
constexpr int kDefaultIterations = 1;
constexpr int kMinIterations = 1;  // the range of SolverSettings::iterations
constexpr int kMaxIterations = 1000;
constexpr double kDefaultDamping = 3e-2;           // SR inverse k of level 3 (see docs/ik.md)
constexpr double kResidualDampingSpeed = 1.0;      // m/s or rad/s: residual at which k reaches its
                                                   // full value under DampingSchedule::kResidual
constexpr double kMinimumDamping = 1e-6;           // floor of the scheduled damping
constexpr double kDefaultTopDamping = 1e-3;        // level-1 damping where J1 loses rank
constexpr double kDefaultTopSingularValue = 1e-2;  // singular values below this get damped
constexpr double kDefaultManipulabilityThreshold = 1e-2;  // w0 for the scheduled damping
constexpr double kDefaultDragGain = 40.0;
constexpr double kDefaultPinGain = 40.0;
constexpr double kDefaultReferenceGain = 2.0;
constexpr double kDefaultLimitGain = 20.0;
constexpr double kDefaultRangeGain = 20.0;
constexpr double kDefaultRangeDamping =
    1e-3;  // level-2 SR k: bounded where it conflicts with the drag
constexpr double kDefaultMaxPositionError = 0.1;     // m, feedback error clamp per step
constexpr double kDefaultMaxOrientationError = 1.0;  // rad
constexpr double kDefaultLimitMargin = 1e-3;         // rad or m inside a limit where a joint stops
constexpr double kDefaultMaxJointStep = 0.2;         // rad or m: largest change of a coordinate per
                                              // iteration; larger steps are scaled down whole
constexpr int kMaxRangeRounds = 4;              // active-set rounds of range rows per iteration
constexpr double kSatisfiedPosition = 1e-3;     // m: a task within this is "satisfied"
constexpr double kSatisfiedOrientation = 1e-2;  // rad

struct SolverSettings {
  double dt = kDefaultTimeStep;  // frame time; each of the iterations integrates dt / iterations
  int iterations = kDefaultIterations;
  double damping = kDefaultDamping;
  DampingSchedule damping_schedule = DampingSchedule::kResidual;
  double manipulability_threshold = kDefaultManipulabilityThreshold;
  double top_damping = kDefaultTopDamping;
  double top_singular_value = kDefaultTopSingularValue;
  double drag_gain = kDefaultDragGain;
  double pin_gain = kDefaultPinGain;
  double reference_gain = kDefaultReferenceGain;
  double limit_gain = kDefaultLimitGain;
  double range_gain = kDefaultRangeGain;
  double range_damping = kDefaultRangeDamping;
  double max_position_error = kDefaultMaxPositionError;
  double max_orientation_error = kDefaultMaxOrientationError;
  double limit_margin = kDefaultLimitMargin;
  double max_joint_step = kDefaultMaxJointStep;
  bool use_joint_weights = true;  // scale joints by the model's ik_weight
  // where the callers that build problems from pins (the session, `pindrag solve`) put them and
  // the drag: hard, pins on level 1 and the drag on level 3 below them and the ranges (a pin
  // holds, a drag it or a range forbids stops short; ik::PinHold projects the pins back after
  // every step), or soft, as in the book: the drag on level 1 is exact and pins on level 3 give
  // way. The solver itself takes each task's level from the Problem.
  bool hard_pins = false;
  // for the session, not the solver: kinematic posing keeps collision shapes above the floor
  // y = 0 and links resting on it where they stand (animator/floor_contacts.hpp)
  bool floor = false;
};

/// The level pins go on under these settings.
inline Priority pin_priority(const SolverSettings& s) { return s.hard_pins ? kTop : kLower; }

/// With hard pins a drag is best effort: it goes on level 3, below the pins (level 1) and the
/// joint ranges (level 2), with this weight, so that the references and soft tasks beside it
/// barely pull on it and the SR damping barely slows it (docs/ik.md, "Pin strength").
constexpr double kHardPinDragWeight = 1000.0;

/// Adds a drag on the level these settings put it: level 1 (soft pins) or level 3 with weight
/// kHardPinDragWeight (hard pins). Returns its id.
int add_drag(LinkTask drag, const SolverSettings& s, Problem& problem);

/// Empty when the settings are usable, else a message naming the first bad field.
std::string validate(const SolverSettings& s);

struct TaskReport {
  int id = 0;
  const char* kind = "";  // "drag", "pin", "reference"
  int index = 0;          // link (drag, pin) or joint (reference)
  Priority priority = kLower;
  double position_error = 0;     // m
  double orientation_error = 0;  // rad
  bool satisfied = false;
};

struct Report {
  /// kRejected: the problem was invalid (message says why) and q was left untouched
  enum class Status { kOk, kRejected };
  Status status = Status::kOk;
  std::string message;
  std::vector<TaskReport> tasks;
  int top_rows = 0;         // level 1 (drag)
  int lower_rows = 0;       // level 3 (pins and references)
  int top_rank = 0;         // numerical rank of level 1
  bool top_damped = false;  // a singular direction of level 1 was damped
  int range_rows = 0;       // level-2 rows: joints at or beyond their ranges (last iteration)
  int iterations = 0;
  double max_joint_speed = 0;  // max |θ̇| over the frame (rad/s or m/s)
  bool step_limited = false;   // an iteration's step was scaled down to max_joint_step
  double limit_violation = 0;  // after the step (rad or m)
  double lower_damping = 0;    // level-3 SR k used (last iteration)
  // the level-3 solve of the last iteration in weight-scaled coordinates: |y| and |Δṗ|;
  // the SR inverse guarantees |y| <= |Δṗ| / (2√k) (Yamane §8.2.3)
  double lower_solution_norm = 0;
  double lower_rhs_norm = 0;
  double microseconds = 0;  // wall time of the step
};

class Solver {
 public:
  Solver(const core::Model& model, const SolverSettings& settings = {});

  /// Advances q by one frame: `settings.iterations` linearize–solve–integrate steps of
  /// dt / iterations each. q is updated in place; data holds the final kinematics.
  /// A problem with a bad link or joint index, or a non-finite target or gain, is rejected:
  /// report().status is kRejected with a message naming the task, and q is not touched.
  /// Allocation-free once the workspace has seen a problem with as many rows on levels 1 and 3
  /// (ik/solver_workspace.hpp).
  const Report& step(const Problem& problem, core::Data& data, Eigen::VectorXd& q);

  const core::Model& model() const { return model_; }
  const SolverSettings& settings() const { return settings_; }
  /// Re-evaluates the report's task errors and range violation at the pose in q and data (the
  /// step's other figures stay): after the caller moved q, e.g. ik::PinHold's corrections.
  void refresh_report(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q) {
    fill_report(problem, data, q);
  }
  void set_settings(const SolverSettings& s) { settings_ = s; }
  const Report& report() const { return report_; }
  /// Joint velocity of the last iteration (nv).
  const Eigen::VectorXd& velocity() const { return ws_.joint_velocity; }

 private:
  /// Empty when every task is usable, else a message naming the first bad one.
  std::string check_problem(const Problem& problem, const Eigen::VectorXd& q) const;
  void fill_rows(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q);
  void append_range_rows(size_t first);  // range_blocks[first..] into level 2
  // the three levels into ws_.x and ws_.joint_velocity; later rounds of one iteration only add
  // range rows, so they reuse level 1 and the factorization of level 3 (ik/solver_levels.cpp)
  void solve_levels(bool first_round);
  void solve_drag_level();
  void invert_damped_drag_gram(const Eigen::Ref<const Eigen::MatrixXd>& G);
  void solve_range_level();
  void solve_pin_level(bool first_round);
  void factorize_pin_level();
  /// One past the last level-3 row of the link task whose rows start at row r.
  int task_rows_end(int r) const;
  double pin_damping();
  void solve_pin_normal_equations();
  void limit_step(double h);
  void fill_report(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q);

  const core::Model& model_;
  SolverSettings settings_;
  Report report_;
  Workspace ws_;
};

}  // namespace ik
