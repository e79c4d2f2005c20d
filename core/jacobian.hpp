// Jacobians: joint motion axes in world, and world-aligned Jacobians of points on links.
#pragma once

#include <Eigen/Core>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Jacobian of a point fixed on a link, world-aligned: ω_W = angular * v, ṗ_W = linear * v.
struct FrameJacobian {
  Matrix3X angular;  // (3 x nv)
  Matrix3X linear;   // (3 x nv)
  FrameJacobian() = default;
  explicit FrameJacobian(int nv) : angular(Matrix3X::Zero(3, nv)), linear(Matrix3X::Zero(3, nv)) {}
};

/// Angular and linear parts of a point's velocity or acceleration, world-aligned.
struct PointMotion {
  Vector3 angular = Vector3::Zero();
  Vector3 linear = Vector3::Zero();
};

/// Forward kinematics plus every joint's motion axes in world: column k of data.J is the spatial
/// velocity (world axes, referenced at the world origin) produced by a unit v_k. Every link's
/// Jacobian is read off these columns (its ancestors' columns, shifted to the point).
/// @return data.J (6 x nv)
const Matrix6X& compute_joint_jacobians(const Model& model, Data& data, const Eigen::VectorXd& q);

/// The same from poses already in data.
/// Requires: forward_kinematics(model, data, q).
const Matrix6X& compute_joint_jacobians(const Model& model, Data& data);

/// The same from the world poses X_W (njoints) into J (6 x nv, sized).
void compute_joint_jacobians(const Model& model, const std::vector<Transform>& X_W, Matrix6X& J);

/// World-aligned Jacobian of the point p_LinkPoint (link frame) on `link`. Allocation-free when
/// J_out is already sized (3 x nv).
/// Requires: compute_joint_jacobians(model, data, q).
void point_jacobian(const Model& model,
                    const Data& data,
                    int link,
                    const Vector3& p_LinkPoint,
                    FrameJacobian& J_out);

/// Velocity of a point on a link. Requires: forward_kinematics(model, data, q, v).
PointMotion point_velocity(const Model& model,
                           const Data& data,
                           int link,
                           const Vector3& p_LinkPoint);

/// J̇·v of a point on a link: its classical acceleration when the joint accelerations are zero.
/// Requires: forward_kinematics(model, data, q, v).
PointMotion point_jdot_v(const Model& model,
                         const Data& data,
                         int link,
                         const Vector3& p_LinkPoint);

/// Classical acceleration of a point on a link. Requires: forward_kinematics(model, data, q, v, a).
PointMotion point_acceleration(const Model& model,
                               const Data& data,
                               int link,
                               const Vector3& p_LinkPoint);

}  // namespace core
