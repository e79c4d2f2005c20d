#include "ik/marker_fit.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <stdexcept>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace ik {

namespace {

// The solver as a damped Gauss–Newton step: K h = 1 makes the pin's desired velocity the whole
// marker error, and the range rows pull back a violation in one step as well.
SolverSettings fit_solver_settings(const MarkerFitSettings& s) {
  SolverSettings o;
  o.dt = 1.0;
  o.iterations = 1;
  o.pin_gain = 1.0;
  o.limit_gain = 1.0;
  o.range_gain = 1.0;
  o.reference_gain = 1.0;
  o.damping = s.damping;
  o.damping_schedule = DampingSchedule::kResidual;
  o.max_position_error = 0.2;
  return o;
}

// Rigid transform (R, t) minimizing Σ |R a_i + t − b_i|² (Kabsch; Horn 1987 in SVD form).
core::Transform kabsch(const std::vector<core::Vector3>& a, const std::vector<core::Vector3>& b) {
  core::Vector3 ca = core::Vector3::Zero(), cb = core::Vector3::Zero();
  for (size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  core::Matrix3 H = core::Matrix3::Zero();
  for (size_t i = 0; i < a.size(); ++i) H += (a[i] - ca) * (b[i] - cb).transpose();
  Eigen::JacobiSVD<core::Matrix3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  core::Matrix3 D = core::Matrix3::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  core::Transform X;
  X.R = svd.matrixV() * D * svd.matrixU().transpose();
  X.p = cb - X.R * ca;
  return X;
}

}  // namespace

std::string validate(const MarkerFitSettings& s) {
  if (s.max_iterations < 1 || s.max_iterations > kMaxIterations)
    return "max_iterations must be in [1, 1000]";
  if (s.first_frame_iterations < 1 || s.first_frame_iterations > kMaxIterations)
    return "first_frame_iterations must be in [1, 1000]";
  if (!std::isfinite(s.tolerance) || s.tolerance <= 0) return "tolerance must be > 0";
  if (s.min_markers < 1) return "min_markers must be >= 1";
  if (s.min_root_markers < 0) return "min_root_markers must be >= 0";
  if (!std::isfinite(s.damping) || s.damping < 0) return "damping must be finite and >= 0";
  if (!std::isfinite(s.reference_weight) || s.reference_weight < 0)
    return "reference_weight must be finite and >= 0";
  if (!std::isfinite(s.restart_rms) || s.restart_rms < 0)
    return "restart_rms must be finite and >= 0";
  if (s.threads < 0) return "threads must be >= 0";
  if (s.chunk_lead_in < 0) return "chunk_lead_in must be >= 0";
  return {};
}

MarkerFitter::MarkerFitter(const core::Model& model,
                           const MarkerSet& set,
                           const MarkerFitSettings& s)
    : model_(model),
      set_(set),
      settings_(s),
      data_(model),
      solver_(model, fit_solver_settings(s)),
      errors_(Eigen::VectorXd::Zero(set.size())) {
  std::string err = check_marker_set(model, set);
  if (err.empty()) err = validate(s);
  if (!err.empty()) throw std::invalid_argument("marker fit: " + err);
  problem_.enforce_ranges = s.enforce_ranges;
  for (const Marker& m : set_.markers) {
    LinkTask t;
    t.role = kPin;
    t.link = m.link;
    t.p_LinkPoint = m.offset;
    t.mode = TaskMode::kPosition;
    problem_.add(Task(t), kLower);
  }
  if (s.reference_weight > 0) {
    add_joint_references(model, core::rest_configuration(model), problem_);
    for (size_t k = set_.markers.size(); k < problem_.entries().size(); ++k) {
      std::get<JointReferenceTask>(problem_.entries()[k].task).weight = s.reference_weight;
    }
  }
}

void MarkerFitter::set_offset(int marker, const core::Vector3& offset) {
  set_.markers[marker].offset = offset;
  std::get<LinkTask>(problem_.entries()[marker].task).p_LinkPoint = offset;
}

int MarkerFitter::count_present(const std::uint8_t* present) const {
  int n = 0;
  for (int j = 0; j < set_.size(); ++j) n += present[j] ? 1 : 0;
  return n;
}

int MarkerFitter::count_root_present(const std::uint8_t* present) const {
  int n = 0;
  for (int j = 0; j < set_.size(); ++j) n += present[j] && set_.markers[j].link == 1 ? 1 : 0;
  return n;
}

void MarkerFitter::place_root(const core::Vector3* targets,
                              const std::uint8_t* present,
                              Eigen::VectorXd& q) {
  if (model_.joint_type[1] != core::JointType::kFree) return;
  core::forward_kinematics(model_, data_, q);
  const bool root_only = count_root_present(present) >= 3;
  std::vector<core::Vector3> model_points, measured;
  for (int j = 0; j < set_.size(); ++j) {
    const Marker& m = set_.markers[j];
    if (!present[j] || (root_only && m.link != 1)) continue;
    model_points.push_back(data_.X_W[m.link] * m.offset);
    measured.push_back(targets[j]);
  }
  if (model_points.size() < 3) return;
  // new root pose X_W' = T X_W; in joint coordinates X_J' = X_PJ⁻¹ T X_PJ X_J
  const core::Transform T = kabsch(model_points, measured);
  const int iq = model_.idx_q[1];
  const core::Transform& X_PJ = model_.X_PJ[1];
  core::Transform X_J{core::quaternion_at(q, iq + 3).toRotationMatrix(), q.segment<3>(iq)};
  const core::Transform X_J_new = X_PJ.inverse() * T * X_PJ * X_J;
  q.segment<3>(iq) = X_J_new.p;
  core::set_quaternion_at(q, iq + 3, core::Quaternion(X_J_new.R).normalized());
}

FrameFit MarkerFitter::fit(const core::Vector3* targets,
                           const std::uint8_t* present,
                           Eigen::VectorXd& q,
                           int iterations) {
  FrameFit out;
  for (int j = 0; j < set_.size(); ++j) {
    auto& t = std::get<LinkTask>(problem_.entries()[j].task);
    t.weight = present[j] ? set_.markers[j].weight : 0.0;
    t.target_W = present[j] ? targets[j] : core::Vector3::Zero();
  }
  for (int it = 0; it < iterations; ++it) {
    const Report& r = solver_.step(problem_, data_, q);
    ++out.iterations;
    if (r.status != Report::Status::kOk) throw std::invalid_argument("marker fit: " + r.message);
    if (r.max_joint_speed < settings_.tolerance) break;  // h = 1: max |Δq| of the step
  }
  compute_errors(targets, present);
  double sum2 = 0;
  for (int j = 0; j < set_.size(); ++j) {
    if (!present[j]) continue;
    sum2 += errors_[j] * errors_[j];
    ++out.present;
  }
  out.rms = out.present > 0 ? std::sqrt(sum2 / out.present) : 0.0;
  return out;
}

void MarkerFitter::compute_errors(const core::Vector3* targets, const std::uint8_t* present) {
  for (int j = 0; j < set_.size(); ++j) {
    const Marker& m = set_.markers[j];
    errors_[j] = present[j] ? (data_.X_W[m.link] * m.offset - targets[j]).norm() : 0.0;
  }
}

}  // namespace ik
