// Recursive Newton–Euler inverse dynamics (RBDA Table 5.1) and its cheap special cases.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Inverse dynamics τ = ID(q, v, a) = H(q) a + b(q, v), with gravity model.gravity.
/// @param q configuration (nq); v, a velocities and accelerations (nv)
/// @return data.tau (nv); also fills data.X_P, data.v, data.f and data.a (which here includes
///         the fictitious world acceleration −g that models gravity)
const Eigen::VectorXd& rnea(const Model& model,
                            Data& data,
                            const Eigen::VectorXd& q,
                            const Eigen::VectorXd& v,
                            const Eigen::VectorXd& a);

/// The same with external forces: f_ext[i] acts on link i, given in link i's frame (moment about
/// the link origin, link axes). f_ext has njoints entries; entry 0 is ignored.
const Eigen::VectorXd& rnea(const Model& model,
                            Data& data,
                            const Eigen::VectorXd& q,
                            const Eigen::VectorXd& v,
                            const Eigen::VectorXd& a,
                            const std::vector<Force>& f_ext);

/// Bias forces b(q, v) = ID(q, v, 0): Coriolis, centrifugal and gravity terms.
const Eigen::VectorXd& bias_forces(const Model& model,
                                   Data& data,
                                   const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& v);

/// Generalized gravity g(q) = ID(q, 0, 0): the joint forces that hold the pose against gravity.
const Eigen::VectorXd& gravity_forces(const Model& model, Data& data, const Eigen::VectorXd& q);

/// A world-frame force f_W applied at world point p_W, as a link-frame spatial force on `link`.
/// Requires: forward_kinematics(model, data, q).
Force link_force_from_world(const Data& data,
                            int link,
                            const Vector3& f_W,
                            const Vector3& p_W,
                            const Vector3& moment_W = Vector3::Zero());

}  // namespace core
