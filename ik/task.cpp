#include "ik/task.hpp"

#include <algorithm>

#include "core/configuration.hpp"

namespace ik {

using core::JointType;

const char* to_string(TaskMode m) {
  switch (m) {
    case TaskMode::kPosition:
      return "position";
    case TaskMode::kOrientation:
      return "orientation";
    case TaskMode::kPose:
      return "pose";
  }
  return "?";
}

const char* to_string(LinkRole r) {
  switch (r) {
    case LinkRole::kDrag:
      return "drag";
    case LinkRole::kPin:
      return "pin";
    case LinkRole::kReference:
      return "reference";
  }
  return "?";
}

namespace {
int mode_rows(TaskMode m) { return m == TaskMode::kPose ? 6 : 3; }
bool has_orientation(TaskMode m) { return m != TaskMode::kPosition; }
bool has_position(TaskMode m) { return m != TaskMode::kOrientation; }

// the error vector shortened to at most max_norm
template <typename V>
V clamped(const V& e, double max_norm) {
  const double n = e.norm();
  return n > max_norm ? V(e * (max_norm / n)) : e;
}
}  // namespace

int task_rows(const core::Model&, const LinkTask& t) { return mode_rows(t.mode); }
int task_rows(const core::Model& model, const JointReferenceTask& t) {
  return core::joint_nv(model.joint_type[t.joint]);
}

void fill_link_task(const core::Model& model,
                    const core::Data& data,
                    const LinkTask& t,
                    double K,
                    const ErrorClamp& clamp,
                    core::FrameJacobian& scratch,
                    Eigen::Ref<Eigen::MatrixXd> J,
                    Eigen::Ref<Eigen::VectorXd> v) {
  core::point_jacobian(model, data, t.link, t.p_LinkPoint, scratch);
  int row = 0;
  if (has_orientation(t.mode)) {
    // ω_d = ω_ref + K log(R_target R_currentᵀ): the world rotation vector to the target
    const Quaternion R_now(data.X_W[t.link].R);
    J.middleRows<3>(row) = scratch.angular;
    const Vector3 e = core::quaternion_log(t.target_R_W * R_now.conjugate());
    v.segment<3>(row) = t.angular_velocity_W + K * clamped(e, clamp.orientation);
    row += 3;
  }
  if (has_position(t.mode)) {
    const Vector3 p_W = data.X_W[t.link] * t.p_LinkPoint;
    J.middleRows<3>(row) = scratch.linear;
    v.segment<3>(row) = t.velocity_W + K * clamped(Vector3(t.target_W - p_W), clamp.position);
  }
}

void fill_reference_task(const core::Model& model,
                         const Eigen::VectorXd& q,
                         const JointReferenceTask& t,
                         double K,
                         const ErrorClamp& clamp,
                         Eigen::Ref<Eigen::MatrixXd> J,
                         Eigen::Ref<Eigen::VectorXd> v) {
  const int iv = model.idx_v[t.joint];
  const int n = core::joint_nv(model.joint_type[t.joint]);
  J.topRows(n).setZero();
  for (int d = 0; d < n; ++d) J(d, iv + d) = 1.0;  // selection rows (Yamane eqs. 8.17–8.20)
  reference_task_velocity(model, q, t, K, clamp, v);
}

void reference_task_velocity(const core::Model& model,
                             const Eigen::VectorXd& q,
                             const JointReferenceTask& t,
                             double K,
                             const ErrorClamp& clamp,
                             Eigen::Ref<Eigen::VectorXd> v) {
  const int iq = model.idx_q[t.joint];
  const int n = core::joint_nv(model.joint_type[t.joint]);
  if (model.joint_type[t.joint] == JointType::kSpherical) {
    const Quaternion R = core::quaternion_at(q, iq);
    const Vector3 e = core::quaternion_log(R.conjugate() * t.R_ref);
    v.head<3>() = t.angular_velocity_ref + K * clamped(e, clamp.orientation);
  } else if (n == 1) {
    const double e = std::clamp(t.q_ref - q[iq], -clamp.orientation, clamp.orientation);
    v[0] = t.velocity_ref + K * e;
  }
}

TaskError link_task_error(const core::Data& data, const LinkTask& t) {
  TaskError e;
  if (has_position(t.mode)) e.position = (t.target_W - data.X_W[t.link] * t.p_LinkPoint).norm();
  if (has_orientation(t.mode)) {
    e.orientation = t.target_R_W.angularDistance(Quaternion(data.X_W[t.link].R));
  }
  return e;
}

TaskError reference_task_error(const core::Model& model,
                               const Eigen::VectorXd& q,
                               const JointReferenceTask& t) {
  TaskError e;
  const int iq = model.idx_q[t.joint];
  if (model.joint_type[t.joint] == JointType::kSpherical) {
    e.orientation = t.R_ref.angularDistance(core::quaternion_at(q, iq));
  } else if (core::joint_nv(model.joint_type[t.joint]) == 1) {
    e.orientation = std::abs(t.q_ref - q[iq]);
  }
  return e;
}

std::optional<TaskMode> task_mode_from_string(std::string_view s) {
  for (TaskMode m : {TaskMode::kPosition, TaskMode::kOrientation, TaskMode::kPose}) {
    if (s == to_string(m)) return m;
  }
  return std::nullopt;
}

}  // namespace ik
