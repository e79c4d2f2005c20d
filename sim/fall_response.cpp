#include "sim/fall_response.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "core/com.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "sim/placement.hpp"

namespace sim {

namespace {

double height_over(const GroundPlane& ground, const core::Vector3& p) {
  return ground.normal.dot(p - ground.point);
}

}  // namespace

std::string validate(const FallSettings& s) {
  if (!(s.com_height >= 0 && s.com_height < 1)) return "fall.com_height: must be in [0, 1)";
  if (!(s.tone >= 0 && std::isfinite(s.tone))) return "fall.tone: must be finite and >= 0";
  if (!(s.damping_ratio >= 0 && std::isfinite(s.damping_ratio))) {
    return "fall.damping_ratio: must be finite and >= 0";
  }
  if (!(s.drag_force >= 0 && std::isfinite(s.drag_force))) {
    return "fall.drag_force: must be finite and >= 0";
  }
  if (!(s.drag_reach > 0 && std::isfinite(s.drag_reach))) {
    return "fall.drag_reach: must be finite and > 0";
  }
  return {};
}

FallResponse::FallResponse(const core::Model& model, const GroundPlane& ground)
    : reach_torque_(Eigen::VectorXd::Zero(model.nv)),
      drive_(Eigen::VectorXd::Zero(model.nv)),
      diagonal_(Eigen::VectorXd::Zero(model.nv)),
      applied_(Eigen::VectorXd::Zero(model.nv)),
      jacobian_(model.nv) {
  core::Data data(model);
  const Eigen::VectorXd q =
      standing_configuration(model, core::neutral_configuration(model), ground);
  core::forward_kinematics(model, data, q);
  standing_height_ = height_over(ground, core::center_of_mass(model, data));
  mass_beyond_ = data.subtree_mass;  // filled by center_of_mass
  const double g = model.gravity.norm();
  weight_ = g * model.total_mass();
  for (int j = 1; j < model.njoints; ++j) {
    double moment = 0;
    for (int k = j; k < model.subtree_end[j]; ++k) {
      const core::SpatialInertia& I = model.inertia[k];
      if (I.mass > 0) moment += I.mass * (data.X_W[k] * I.com() - data.X_W[j].p).norm();
    }
    const int nv = core::joint_nv(model.joint_type[j]);
    reach_torque_.segment(model.idx_v[j], nv).setConstant(g * moment);
  }
}

bool FallResponse::update(const core::Model& model,
                          core::Data& data,
                          const GroundPlane& ground,
                          bool on_ground,
                          const FallSettings& settings) {
  if (!settings.enabled || fallen_ || !on_ground) return fallen_;
  const double height = height_over(ground, core::center_of_mass(model, data));
  fallen_ = height < settings.com_height * standing_height_;
  return fallen_;
}

void FallResponse::prepare(const core::Model& model,
                           const core::Data& data,
                           const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v,
                           const Eigen::VectorXd& tau,
                           const ik::Problem& problem,
                           const FallSettings& settings,
                           double h) {
  drive_ = tau;
  diagonal_.setZero();
  for (const ik::Problem::Entry& e : problem.entries()) {
    if (const auto* r = std::get_if<ik::JointReferenceTask>(&e.task)) {
      add_tone(model, data, q, v, *r, settings, h);
    } else if (const auto* t = std::get_if<ik::LinkTask>(&e.task)) {
      if (t->role == ik::kDrag && t->mode != ik::TaskMode::kOrientation) {
        add_drag_spring(model, data, v, *t, settings);
      }
    }
  }
}

void FallResponse::finish(const Eigen::VectorXd& a) {
  applied_ = drive_;
  applied_.array() -= diagonal_.array() * a.array();
}

void FallResponse::add_tone(const core::Model& model,
                            const core::Data& data,
                            const Eigen::VectorXd& q,
                            const Eigen::VectorXd& v,
                            const ik::JointReferenceTask& reference,
                            const FallSettings& settings,
                            double h) {
  // τ = K e − D q̇ with D = 2 ζ √(K H_jj), at the step's end: K e − (D + h K) v in the drive,
  // h D + h² K on the diagonal
  const auto add = [&](int c, double error) {
    const double K = settings.tone * reach_torque_[c];
    const double D = 2 * settings.damping_ratio * std::sqrt(K * std::max(data.M(c, c), 0.0));
    drive_[c] += K * error - (D + h * K) * v[c];
    diagonal_[c] += h * D + h * h * K;
  };
  const int c = model.idx_v[reference.joint];
  switch (model.joint_type[reference.joint]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      add(c, reference.q_ref - q[model.idx_q[reference.joint]]);
      break;
    case core::JointType::kSpherical: {
      // log(Rᵀ R_ref): the rotation from the joint's orientation to its reference, child frame
      const core::Quaternion R = core::quaternion_at(q, model.idx_q[reference.joint]);
      const core::Vector3 e = core::quaternion_log(R.conjugate() * reference.R_ref);
      for (int k = 0; k < 3; ++k) add(c + k, e[k]);
      break;
    }
    default:
      break;
  }
}

void FallResponse::add_drag_spring(const core::Model& model,
                                   const core::Data& data,
                                   const Eigen::VectorXd& v,
                                   const ik::LinkTask& drag,
                                   const FallSettings& settings) {
  // F = k (target − p) − c ṗ with the spring's pull at most F_max, as joint forces Jᵀ F
  const double f_max = settings.drag_force * weight_;
  const double k = f_max / settings.drag_reach;
  const double c = 2 * std::sqrt(k * mass_beyond_[drag.link]);
  core::point_jacobian(model, data, drag.link, drag.p_LinkPoint, jacobian_);
  const core::Vector3 p = data.X_W[drag.link] * drag.p_LinkPoint;
  const core::Vector3 p_dot = jacobian_.linear * v;
  core::Vector3 F = k * (drag.target_W - p);
  const double norm = F.norm();
  if (norm > f_max) F *= f_max / norm;
  F -= c * p_dot;
  drive_.noalias() += jacobian_.linear.transpose() * F;
}

}  // namespace sim
