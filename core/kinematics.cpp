#include "core/kinematics.hpp"

#include <cmath>

#include "core/configuration.hpp"

namespace core {

namespace {
// R * rotation about principal axis k by angle q (fast path for revolute joints)
Matrix3 rotate_about_axis(const Matrix3& R, int k, double q) {
  const double c = std::cos(q), s = std::sin(q);
  Matrix3 out;
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  out.col(k) = R.col(k);
  out.col(k1) = c * R.col(k1) + s * R.col(k2);
  out.col(k2) = -s * R.col(k1) + c * R.col(k2);
  return out;
}
}  // namespace

Transform joint_transform(const Model& model, int i, const Eigen::VectorXd& q) {
  const Transform& X = model.X_PJ[i];
  const int iq = model.idx_q[i];
  switch (model.joint_type[i]) {
    case JointType::kFixed:
      return X;
    case JointType::kRevolute: {
      const int k = model.axis_index[i];
      if (k >= 0) return {rotate_about_axis(X.R, k, q[iq]), X.p};
      return {X.R * Eigen::AngleAxisd(q[iq], model.axis[i]).toRotationMatrix(), X.p};
    }
    case JointType::kPrismatic:
      return {X.R, X.p + X.R * (model.axis[i] * q[iq])};
    case JointType::kSpherical:
      return {X.R * quaternion_at(q, iq).toRotationMatrix(), X.p};
    case JointType::kFree:
      return {X.R * quaternion_at(q, iq + 3).toRotationMatrix(), X.p + X.R * q.segment<3>(iq)};
  }
  return X;
}

const std::vector<Transform>& forward_kinematics(const Model& model,
                                                 Data& data,
                                                 const Eigen::VectorXd& q) {
  data.X_W[0] = Transform::Identity();
  for (int i = 1; i < model.njoints; ++i) {
    const Transform& X_WP = data.X_W[model.parent[i]];
    const int k = model.axis_index[i];
    if (model.joint_type[i] == JointType::kRevolute && k >= 0 &&
        model.placement_is_translation[i]) {
      // the common case: a hinge about a frame axis with an unrotated placement; rotate the
      // parent's world axes directly instead of composing two 3×3 rotations
      const double a = q[model.idx_q[i]];
      data.X_P[i] = {rotate_about_axis(Matrix3::Identity(), k, a), model.X_PJ[i].p};
      data.X_W[i] = {rotate_about_axis(X_WP.R, k, a), X_WP.R * model.X_PJ[i].p + X_WP.p};
    } else {
      data.X_P[i] = joint_transform(model, i, q);
      data.X_W[i] = X_WP * data.X_P[i];
    }
  }
  return data.X_W;
}

Motion joint_motion(const Model& model, int i, const Eigen::VectorXd& v) {
  const int iv = model.idx_v[i];
  switch (model.joint_type[i]) {
    case JointType::kFixed:
      return Motion::Zero();
    case JointType::kRevolute:
      return {model.axis[i] * v[iv], Vector3::Zero()};
    case JointType::kPrismatic:
      return {Vector3::Zero(), model.axis[i] * v[iv]};
    case JointType::kSpherical:
      return {v.segment<3>(iv), Vector3::Zero()};
    case JointType::kFree:
      return {v.segment<3>(iv), v.segment<3>(iv + 3)};
  }
  return Motion::Zero();
}

void forward_kinematics(const Model& model,
                        Data& data,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v) {
  forward_kinematics(model, data, q);
  data.v[0] = Motion::Zero();
  data.a_bias[0] = Motion::Zero();
  for (int i = 1; i < model.njoints; ++i) {
    const int p = model.parent[i];
    // v_i = X_{i,p} v_p + S_i q̇_i ;  a_i = X_{i,p} a_p + v_i × S_i q̇_i   (S constant in link frame)
    const Motion vJ = joint_motion(model, i, v);
    data.v[i] = data.X_P[i].act_inverse(data.v[p]) + vJ;
    data.a_bias[i] = data.X_P[i].act_inverse(data.a_bias[p]) + data.v[i].cross(vJ);
  }
}

void forward_kinematics(const Model& model,
                        Data& data,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v,
                        const Eigen::VectorXd& a) {
  forward_kinematics(model, data, q, v);
  data.a[0] = Motion::Zero();
  for (int i = 1; i < model.njoints; ++i) {
    data.a[i] = data.X_P[i].act_inverse(data.a[model.parent[i]]) + joint_motion(model, i, a) +
                data.v[i].cross(joint_motion(model, i, v));
  }
}

}  // namespace core
