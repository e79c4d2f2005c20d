// Joint ranges in the IK: 1-DOF limits (Yamane eq. 8.23) and spherical swing–twist ranges
// (Yamane §8.3.5). Handled here and nowhere else.
//
// Rows appear only while needed, as in the book, plus a predictive pass that keeps them from
// chattering on and off: a joint that the tentative step would carry across its range gets a row
// that stops it at the boundary (less a small margin), and the step is solved again. A joint
// already outside its range gets the book's row: 1-DOF joints are pulled back to the violated
// limit, spherical joints toward their standard orientation.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/model.hpp"

namespace ik {

/// One range row block: 1 row for a 1-DOF joint, 3 rows (child-frame ω) for a spherical joint.
struct RangeRow {
  int joint = 0;
  int rows = 1;
  core::Vector3 desired = core::Vector3::Zero();  // desired joint velocity (first `rows` entries)
};

/// Appends rows for joints outside their ranges; `flags[joint]` is set for each.
void collect_range_violations(const core::Model& model,
                              const Eigen::VectorXd& q,
                              double limit_gain,
                              double range_gain,
                              std::vector<RangeRow>& rows,
                              std::vector<char>& flags);

/// Appends rows for joints (not yet flagged) that q ⊕ h v would carry outside their ranges.
/// Returns the number of rows added.
int collect_range_predictions(const core::Model& model,
                              const Eigen::VectorXd& q,
                              const Eigen::VectorXd& v,
                              double h,
                              double margin,
                              std::vector<RangeRow>& rows,
                              std::vector<char>& flags);

/// Largest violation over all joints (rad or m; 0 when every joint is in range).
double max_range_violation(const core::Model& model, const Eigen::VectorXd& q);

}  // namespace ik
