// The two-level pin-and-drag IK solver (Yamane §8.2.4, digest §2.2).
//
// Top level: the drag rows J1 θ̇ = v1, solved exactly with the (joint-weighted) pseudoinverse;
// damped only along directions where J1 loses rank (fixed root, stretched limb).
// Lower level: pins, references and range rows J2 θ̇ = v2, solved with the SR inverse in the
// null space of the top: y = (J2 W)* (v2 − J2 θ̇0), θ̇ = θ̇0 + W y, with the projector
// W = E − J1⁺ J1 applied implicitly (never an N×N matrix).
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
#include "ik/sr_inverse.hpp"

namespace ik {

// Default tuning (named so the accuracy-versus-time report can sweep them). Gains are in 1/s;
// with explicit integration the error shrinks by (1 − K h) per step, so K h ≤ 1 (digest §2.3).
constexpr double kDefaultTimeStep = 1.0 / 60.0;
constexpr int kDefaultIterations = 1;
constexpr double kDefaultDamping = 1e-3;         // SR inverse k of the lower level
constexpr double kDefaultTopDamping = 1e-3;      // top-level damping where J1 loses rank
constexpr double kDefaultTopSingularValue = 1e-2;  // singular values below this get damped
constexpr double kDefaultManipulabilityThreshold = 1e-2;  // w0 for the scheduled damping
constexpr double kDefaultDragGain = 40.0;
constexpr double kDefaultPinGain = 40.0;
constexpr double kDefaultReferenceGain = 2.0;
constexpr double kDefaultLimitGain = 20.0;
constexpr double kDefaultRangeGain = 20.0;
constexpr double kDefaultRangeWeight = 100.0;    // range rows outweigh pins (1) on the lower level
constexpr double kDefaultMaxPositionError = 0.2;   // m, feedback error clamp per step
constexpr double kDefaultMaxOrientationError = 1.0;  // rad
constexpr double kDefaultLimitMargin = 1e-3;     // rad or m inside a limit where a joint stops
constexpr double kSatisfiedPosition = 1e-3;      // m: a task within this is "satisfied"
constexpr double kSatisfiedOrientation = 1e-2;   // rad

struct SolverSettings {
  double dt = kDefaultTimeStep;  // frame time; each of the iterations integrates dt / iterations
  int iterations = kDefaultIterations;
  double damping = kDefaultDamping;
  DampingSchedule damping_schedule = DampingSchedule::kConstant;
  double manipulability_threshold = kDefaultManipulabilityThreshold;
  double top_damping = kDefaultTopDamping;
  double top_singular_value = kDefaultTopSingularValue;
  double drag_gain = kDefaultDragGain;
  double pin_gain = kDefaultPinGain;
  double reference_gain = kDefaultReferenceGain;
  double limit_gain = kDefaultLimitGain;
  double range_gain = kDefaultRangeGain;
  double range_weight = kDefaultRangeWeight;
  double max_position_error = kDefaultMaxPositionError;
  double max_orientation_error = kDefaultMaxOrientationError;
  double limit_margin = kDefaultLimitMargin;
  bool use_joint_weights = true;  // scale joints by the model's ik_weight
};

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
  std::vector<TaskReport> tasks;
  int top_rows = 0;
  int lower_rows = 0;
  int top_rank = 0;          // numerical rank of the top level
  bool top_damped = false;   // a singular direction of the top level was damped
  int range_rows = 0;        // rows added for joints at or beyond their ranges (last iteration)
  int iterations = 0;
  double max_joint_speed = 0;  // max |θ̇| over the frame (rad/s or m/s)
  double limit_violation = 0;  // after the step (rad or m)
  double lower_damping = 0;    // SR k used (last iteration)
  double microseconds = 0;     // wall time of the step
};

class Solver {
 public:
  Solver(const core::Model& model, const SolverSettings& settings = {});

  /// Advances q by one frame: `settings.iterations` linearize–solve–integrate steps of
  /// dt / iterations each. q is updated in place; data holds the final kinematics.
  /// Allocation-free once the workspace has seen a problem of this size.
  const Report& step(const Problem& problem, core::Data& data, Eigen::VectorXd& q);

  const SolverSettings& settings() const { return settings_; }
  void set_settings(const SolverSettings& s) { settings_ = s; }
  const Report& report() const { return report_; }
  /// Joint velocity of the last iteration (nv).
  const Eigen::VectorXd& velocity() const { return qdot_; }

 private:
  void fill_rows(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q);
  void append_range_rows(size_t first);
  void solve_levels();
  void fill_report(const Problem& problem, const core::Data& data, const Eigen::VectorXd& q);

  const core::Model& model_;
  SolverSettings settings_;
  Report report_;
  // rows: top (J1, v1) and lower (J2, v2, row scale √weight); joint scale 1/√w
  Eigen::MatrixXd J1_, J2_;
  Eigen::VectorXd v1_, v2_, row_scale2_, col_scale_;
  int m1_ = 0, m2_ = 0;
  // top-level factors
  Eigen::MatrixXd J1s_, J2s_;  // rows and columns scaled by the weights
  Eigen::MatrixXd G_, E_, P_, JJ_, S_;
  Eigen::VectorXd t1_, x0_, dp_, y_, qdot_, scaled_;
  SrInverse sr_;
  core::FrameJacobian point_;
  std::vector<RangeRow> range_rows_;
  std::vector<char> range_flags_;
};

}  // namespace ik
