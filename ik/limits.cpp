#include "ik/limits.hpp"

#include <cmath>

#include "core/configuration.hpp"
#include "core/swing_twist.hpp"

namespace ik {

using core::JointType;

namespace {
bool one_dof(JointType t) { return t == JointType::kRevolute || t == JointType::kPrismatic; }

bool has_spherical_range(const core::Model& model, int i) {
  return model.joint_type[i] == JointType::kSpherical && !model.spherical_range[i].empty();
}

bool spherical_in_range(const core::Model& model, int i, const core::Quaternion& r) {
  return core::joint_range_status(model, i, r).inside;
}
}  // namespace

void collect_range_violations(const core::Model& model,
                              const Eigen::VectorXd& q,
                              double limit_gain,
                              double range_gain,
                              std::vector<RangeRow>& rows,
                              std::vector<char>& flags) {
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    if (one_dof(model.joint_type[i])) {
      const core::JointLimits& L = model.limits[i];
      // φ̇_d = K (φ_max − φ) above the range, K (φ_min − φ) below it (Yamane eq. 8.23)
      if (q[iq] > L.upper) {
        rows.push_back({i, 1, core::Vector3(limit_gain * (L.upper - q[iq]), 0, 0)});
        flags[i] = 1;
      } else if (q[iq] < L.lower) {
        rows.push_back({i, 1, core::Vector3(limit_gain * (L.lower - q[iq]), 0, 0)});
        flags[i] = 1;
      }
    } else if (has_spherical_range(model, i)) {
      const core::Quaternion r = core::quaternion_at(q, iq);
      if (!spherical_in_range(model, i, r)) {
        // ω_d = K log(Rᵀ R_S): toward the standard orientation, child frame (Yamane §8.3.5)
        const core::Vector3 w =
            range_gain * core::quaternion_log(r.conjugate() * model.standard_orientation[i]);
        rows.push_back({i, 3, w});
        flags[i] = 1;
      }
    }
  }
}

int collect_range_predictions(const core::Model& model,
                              const Eigen::VectorXd& q,
                              const Eigen::VectorXd& v,
                              double h,
                              double margin,
                              std::vector<RangeRow>& rows,
                              std::vector<char>& flags) {
  int added = 0;
  for (int i = 1; i < model.njoints; ++i) {
    if (flags[i]) continue;
    const int iq = model.idx_q[i];
    const int iv = model.idx_v[i];
    if (one_dof(model.joint_type[i])) {
      const core::JointLimits& L = model.limits[i];
      const double next = q[iq] + h * v[iv];
      // stop at the boundary less the margin; a joint already inside the margin band is held
      if (v[iv] > 0 && next > L.upper - margin) {
        rows.push_back({i, 1, core::Vector3(std::max(0.0, L.upper - margin - q[iq]) / h, 0, 0)});
      } else if (v[iv] < 0 && next < L.lower + margin) {
        rows.push_back({i, 1, core::Vector3(std::min(0.0, L.lower + margin - q[iq]) / h, 0, 0)});
      } else {
        continue;
      }
    } else if (has_spherical_range(model, i)) {
      const core::Quaternion r = core::quaternion_at(q, iq);
      const core::Quaternion next = r * core::quaternion_exp(v.segment<3>(iv) * h);
      if (spherical_in_range(model, i, next)) continue;
      rows.push_back({i, 3, core::Vector3::Zero()});  // hold the joint where it is
    } else {
      continue;
    }
    flags[i] = 1;
    ++added;
  }
  return added;
}

double max_range_violation(const core::Model& model, const Eigen::VectorXd& q) {
  double worst = 0;
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    if (one_dof(model.joint_type[i])) {
      const core::JointLimits& L = model.limits[i];
      worst = std::max({worst, q[iq] - L.upper, L.lower - q[iq]});
    } else if (has_spherical_range(model, i)) {
      worst =
          std::max(worst, core::joint_range_status(model, i, core::quaternion_at(q, iq)).violation);
    }
  }
  return worst;
}

}  // namespace ik
