// Hard pins as constraints. A solver step is a linearization: a drag that bends knees starting
// almost straight moves joints by tenths of a radian in a frame, and a pin that the step keeps
// still to first order drifts by the second-order term (millimetres per frame), or by the share
// of a forbidden drag that level 1's damping gives it. PinHold projects the pose back onto the
// pins after the step: Gauss–Newton steps on the hard pins (the pins on level 1) alone, the
// least change of pose that puts them back, until every hard pin is within a tolerance. Newton
// converges quadratically, so one or two corrections reach a tenth of a millimetre (docs/ik.md,
// "Pin strength").
#pragma once

#include <Eigen/Core>

#include <vector>
#include "core/data.hpp"
#include "core/model.hpp"

#include "ik/limits.hpp"
#include "ik/problem.hpp"
#include "ik/solver.hpp"

namespace ik {

constexpr double kDefaultHardPinTolerance = 1e-4;  // m (and rad for orientation rows)
constexpr int kDefaultMaxPinCorrections = 3;

struct PinHoldReport {
  int corrections = 0;      // correcting steps taken
  double error_before = 0;  // largest hard-pin error after the step (m or rad)
  double error_after = 0;   // ... and after the corrections
};

class PinHold {
 public:
  /// The corrections run on a solver of their own, so the caller's keeps the report of its step.
  explicit PinHold(const core::Model& model) : solver_(model) {}

  /// After solver.step(problem, data, q): while the largest error of a hard pin exceeds
  /// `tolerance` and the last correction at least halved it, takes a correcting step, at most
  /// `max_corrections`. A correction solves the hard pins alone on level 1 with a gain of one
  /// over the sub-step (the whole error in one Gauss–Newton step); a joint it would carry out of
  /// its range is locked and the correction solved again. A correction that does not reduce
  /// the error is undone.
  /// `settings` are those of the step (its dt and iterations set the gain). Allocation-free
  /// once it has seen a problem of this size.
  const PinHoldReport& hold(const SolverSettings& settings,
                            const Problem& problem,
                            core::Data& data,
                            Eigen::VectorXd& q,
                            double tolerance = kDefaultHardPinTolerance,
                            int max_corrections = kDefaultMaxPinCorrections);

  /// The largest error of a hard pin of `problem` (m or rad); needs forward kinematics.
  static double hard_pin_error(const Problem& problem, const core::Data& data);

  const PinHoldReport& report() const { return report_; }

 private:
  void build_correction(const Problem& problem, double gain);
  /// One correcting step from start_q_ (= q); false when it could not be taken inside the ranges.
  bool correct_once(const Problem& problem, core::Data& data, Eigen::VectorXd& q, double gain);
  static constexpr int kMaxLockRounds = 4;

  Solver solver_;
  Problem correction_;
  PinHoldReport report_;
  Eigen::VectorXd start_q_;  // the pose before the current correction
  std::vector<RangeRow> range_rows_;
  std::vector<char> range_flags_, range_flags_before_;
};

}  // namespace ik
