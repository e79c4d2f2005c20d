#include "core/kinematics.hpp"

#include <cmath>

#include "core/configuration.hpp"
#include "core/hinge.hpp"

namespace core {

namespace {
// R * (rotation about principal axis K): R's columns k1, k2 mix
template <int K>
inline Matrix3 rotate_columns(const Matrix3& R, const AxisRotation<K>& r) {
  constexpr int k1 = AxisRotation<K>::k1, k2 = AxisRotation<K>::k2;
  Matrix3 out;
  out.col(K) = R.col(K);
  out.col(k1) = r.c * R.col(k1) + r.s * R.col(k2);
  out.col(k2) = r.c * R.col(k2) - r.s * R.col(k1);
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
      if (k >= 0) {
        return with_axis(k, [&](auto axis) -> Transform {
          return {rotate_columns(X.R, hinge_rotation<axis()>(model, i, q)), X.p};
        });
      }
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

void forward_kinematics(const Model& model,
                        const Eigen::VectorXd& q,
                        std::vector<Transform>& X_P,
                        std::vector<Transform>& X_W) {
  X_W[0] = Transform::Identity();
  for (int i = 1; i < model.njoints; ++i) {
    const Transform& X_WP = X_W[model.parent[i]];
    if (is_hinge(model, i)) {
      // the common case: a hinge about a frame axis with an unrotated placement; rotate the
      // parent's world axes directly instead of composing two 3×3 rotations
      with_axis(model.axis_index[i], [&](auto axis) {
        const auto r = hinge_rotation<axis()>(model, i, q);
        const Vector3& p = model.X_PJ[i].p;
        X_P[i] = {r.matrix(), p};
        const Matrix3& R = X_WP.R;
        X_W[i] = {rotate_columns(R, r),
                  R.col(0) * p[0] + R.col(1) * p[1] + R.col(2) * p[2] + X_WP.p};
      });
    } else {
      X_P[i] = joint_transform(model, i, q);
      X_W[i] = X_WP * X_P[i];
    }
  }
}

const std::vector<Transform>& forward_kinematics(const Model& model,
                                                 Data& data,
                                                 const Eigen::VectorXd& q) {
  forward_kinematics(model, q, data.X_P, data.X_W);
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
