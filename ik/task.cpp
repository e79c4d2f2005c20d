#include "ik/task.hpp"

#include <algorithm>
#include <cassert>
#include <type_traits>

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
                    Eigen::Ref<Eigen::MatrixXd> J,
                    Eigen::Ref<Eigen::VectorXd> v) {
  const Vector3 p_W = data.X_W[t.link] * t.p_LinkPoint;
  // the point's Jacobian rows, written straight into J: zero, then the columns of the link's
  // root path (orientation rows first)
  const int angular_row = has_orientation(t.mode) ? 0 : -1;
  const int linear_row = !has_position(t.mode) ? -1 : angular_row < 0 ? 0 : 3;
  const int rows = mode_rows(t.mode);
  assert(J.rows() == rows && J.cols() == model.nv);
  double* const base = J.data();
  const Eigen::Index stride = J.outerStride();
  // a fixed count per column: a runtime one becomes a string store, slow to start for 6 entries
  const auto zero_columns = [&]<int Rows>(std::integral_constant<int, Rows>) {
    for (Eigen::Index c = 0; c < J.cols(); ++c) {
      double* const column = base + c * stride;
      for (int r = 0; r < Rows; ++r) column[r] = 0.0;
    }
  };
  if (rows == 6) {
    zero_columns(std::integral_constant<int, 6>{});
  } else {
    zero_columns(std::integral_constant<int, 3>{});
  }
  core::write_point_jacobian_rows(model, data, t.link, p_W, angular_row, linear_row, J);
  if (angular_row >= 0) {
    // ω_d = ω_ref + K log(R_target R_currentᵀ): the world rotation vector to the target
    const Quaternion R_now(data.X_W[t.link].R);
    const Vector3 e = core::quaternion_log(t.target_R_W * R_now.conjugate());
    v.segment<3>(angular_row) = t.angular_velocity_W + K * clamped(e, clamp.orientation);
  }
  if (linear_row >= 0) {
    v.segment<3>(linear_row) =
        t.velocity_W + K * clamped(Vector3(t.target_W - p_W), clamp.position);
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
