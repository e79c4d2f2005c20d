// Hard joint limits (the hard_limits effect): a joint that this step would carry past its limit
// is stopped there by an impulse, so its velocity into the limit is removed at impact and the
// limit is never crossed afterwards (the impact and acceleration constraints of the adaptive-
// dynamics paper, digest §2.15). The impulses act through the joint-space inertia, so the rest
// of the body keeps its momentum: Δv = H⁻¹ Sᵀ λ with (S H⁻¹ Sᵀ) λ = v_allowed − S v.
// A 1-DOF joint that would cross its limit within the step stops (velocity 0 into the limit) and
// is placed on the limit after the step (a position correction of at most h |v|); a spherical
// joint that would leave its swing–twist range is held for the step (three rows ask for ω = 0).
// The impulses are found by projected Gauss–Seidel (complementarity: an upper stop only pushes
// down, a lower one only up, and releases a joint that moves away).
#include <algorithm>

#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/swing_twist.hpp"
#include "sim/world.hpp"

namespace sim {

namespace {

bool one_dof(core::JointType t) {
  return t == core::JointType::kRevolute || t == core::JointType::kPrismatic;
}

// the rows of joints that q ⊕ h v would carry past their limits
void collect_rows(const core::Model& m,
                  const Eigen::VectorXd& q,
                  const Eigen::VectorXd& v,
                  double h,
                  std::vector<LimitRow>& rows) {
  for (int i = 1; i < m.njoints; ++i) {
    const int iq = m.idx_q[i], iv = m.idx_v[i];
    if (one_dof(m.joint_type[i])) {
      const core::JointLimits& L = m.limits[i];
      const double next = q[iq] + h * v[iv];
      // an impact: the joint stops (its velocity into the limit becomes 0) and is placed on the
      // limit after the step
      if (next > L.upper) rows.push_back({iv, 0.0, +1, iq, L.upper});
      if (next < L.lower) rows.push_back({iv, 0.0, -1, iq, L.lower});
    } else if (m.joint_type[i] == core::JointType::kSpherical && !m.spherical_range[i].empty()) {
      const core::Quaternion r = core::quaternion_at(q, iq);
      const core::Quaternion next = r * core::quaternion_exp(h * v.segment<3>(iv));
      auto inside = [&](const core::Quaternion& x) {
        return core::joint_range_status(m, i, x).inside;
      };
      if (!inside(next) && inside(r)) {
        for (int d = 0; d < 3; ++d) rows.push_back({iv + d, 0.0, 0, -1, 0.0});
      }
    }
  }
}

// rows of joints that q ⊕ h v carries past their limits and that have no row yet
void collect_new_rows(const core::Model& m,
                      const Eigen::VectorXd& q,
                      const Eigen::VectorXd& v,
                      double h,
                      std::vector<LimitRow>& rows) {
  std::vector<LimitRow> fresh;
  collect_rows(m, q, v, h, fresh);
  for (const LimitRow& f : fresh) {
    const bool known = std::any_of(rows.begin(), rows.end(), [&](const LimitRow& r) {
      return r.coordinate == f.coordinate && r.side == f.side;
    });
    if (!known) rows.push_back(f);
  }
}

}  // namespace

void World::run_limit_projection() {
  counters_.count(Stage::kLimitProjection);
  const double h = settings_.step;
  limit_snaps_.clear();
  for (int b = 0; b < body_count(); ++b) {
    const core::Model& m = *bodies_[b].model;
    Eigen::VectorXd& v = v_next_[b];
    limit_rows_.clear();
    collect_rows(m, bodies_[b].q, v, h, limit_rows_);
    if (limit_rows_.empty()) continue;
    Work& w = work_[b];
    if (!w.mass_matrix_ready) {
      counters_.count(Stage::kMassMatrix);
      core::crba(*w.dynamics, w.data, bodies_[b].q);
      core::factorize_mass_matrix(*w.dynamics, w.data);
      w.mass_matrix_ready = true;
    }
    // projected Gauss–Seidel on the impulses λ (one per row, signed by its side); rows for joints
    // that the impulses of others push toward a limit join in later rounds
    limit_columns_.resize(m.nv, 0);
    limit_impulses_.clear();
    for (int round = 0; round < 4; ++round) {
      const int k = static_cast<int>(limit_rows_.size());
      const int known = static_cast<int>(limit_impulses_.size());
      limit_columns_.conservativeResize(m.nv, k);
      limit_impulses_.resize(k, 0.0);
      for (int r = known; r < k; ++r) {
        limit_columns_.col(r).setZero();
        limit_columns_(limit_rows_[r].coordinate, r) = 1;
        core::solve_mass_matrix(*w.dynamics, w.data, limit_columns_.col(r));  // H⁻¹ e_c
      }
      for (int sweep = 0; sweep < 50; ++sweep) {
        double change = 0;
        for (int r = 0; r < k; ++r) {
          const LimitRow& row = limit_rows_[r];
          const double W = limit_columns_(row.coordinate, r);
          double lambda = limit_impulses_[r] + (row.allowed - v[row.coordinate]) / W;
          if (row.side > 0) lambda = std::min(lambda, 0.0);  // an upper stop only pushes down
          if (row.side < 0) lambda = std::max(lambda, 0.0);
          const double delta = lambda - limit_impulses_[r];
          if (delta == 0) continue;
          v.noalias() += delta * limit_columns_.col(r);
          limit_impulses_[r] = lambda;
          change = std::max(change, std::abs(delta * W));
        }
        if (change < 1e-12) break;
      }
      // joints the impulses carried toward a limit of their own get rows next round
      const size_t before = limit_rows_.size();
      collect_new_rows(m, bodies_[b].q, v, h, limit_rows_);
      if (limit_rows_.size() == before) break;
    }
    for (size_t r = 0; r < limit_impulses_.size(); ++r) {
      const LimitRow& row = limit_rows_[r];
      if (row.q_index >= 0 && limit_impulses_[r] != 0) {
        limit_snaps_.push_back({b, row.q_index, row.limit});
      }
    }
  }
}

}  // namespace sim
