// Forward kinematics: poses, spatial velocities and accelerations of every link.
#pragma once

#include <Eigen/Core>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Pose of joint i's frame in its parent link for configuration q: X_PJ * X_J(q).
Transform joint_transform(const Model& model, int i, const Eigen::VectorXd& q);

/// World poses of all links.
/// @return data.X_W (njoints); also fills data.X_P
const std::vector<Transform>& forward_kinematics(const Model& model,
                                                 Data& data,
                                                 const Eigen::VectorXd& q);

/// The same into the given arrays (njoints each): X_P[i] pose of link i in its parent, X_W[i] in
/// the world (for kernels that keep their own poses).
void forward_kinematics(const Model& model,
                        const Eigen::VectorXd& q,
                        std::vector<Transform>& X_P,
                        std::vector<Transform>& X_W);

/// Poses and spatial velocities (data.v), and the velocity-product accelerations at zero joint
/// acceleration (data.a_bias, the J̇v term). RBDA Table 3.1 first pass.
void forward_kinematics(const Model& model,
                        Data& data,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v);

/// As above, plus the spatial accelerations for joint acceleration a (data.a).
void forward_kinematics(const Model& model,
                        Data& data,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v,
                        const Eigen::VectorXd& a);

/// Spatial velocity (link frame) contributed by the joint's own velocity: S_i v_i.
Motion joint_motion(const Model& model, int i, const Eigen::VectorXd& v);

}  // namespace core
