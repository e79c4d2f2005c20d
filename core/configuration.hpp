// The configuration manifold: q (nq) and v (nv) differ once a spherical or free joint exists.
// This is the one place that defines how they relate (DESIGN.md §2):
//  - spherical q = unit quaternion (w, x, y, z); v = angular velocity in the child frame
//  - free q = (position in the parent frame, unit quaternion); v = [ω; v] body twist (child frame)
//  - integrate(q, v, dt) follows the exponential map; difference(q0, q1) is its inverse.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "core/model.hpp"

namespace core {

struct State {
  Eigen::VectorXd q;  // configuration (nq)
  Eigen::VectorXd v;  // velocity (nv)
};

/// Zero joint angles, identity rotations, root at the origin.
Eigen::VectorXd neutral_configuration(const Model& model);
State neutral_state(const Model& model);

/// Where posing starts: the neutral configuration with every 1-DOF joint moved off the ends of
/// its range, by 2 % of the way from zero to the middle of its limits (a knee with limits
/// [-5°, 135°] rests at 1.3°), and clamped into its limits. Zero is where limbs are straight,
/// a singular configuration for IK (digest §4 #1): a straight leg cannot start to shorten, so
/// pinned feet would slide instead of the knees bending. Joints with symmetric limits stay at 0.
Eigen::VectorXd rest_configuration(const Model& model);

/// q_out = q ⊕ v dt on the manifold. q_out may alias q. Allocation-free.
void integrate(const Model& model,
               const Eigen::VectorXd& q,
               const Eigen::VectorXd& v,
               double dt,
               Eigen::VectorXd& q_out);
Eigen::VectorXd integrate(const Model& model,
                          const Eigen::VectorXd& q,
                          const Eigen::VectorXd& v,
                          double dt);

/// v such that integrate(q0, v, 1) == q1 (shortest rotation for spherical and free joints).
void difference(const Model& model,
                const Eigen::VectorXd& q0,
                const Eigen::VectorXd& q1,
                Eigen::VectorXd& v_out);
Eigen::VectorXd difference(const Model& model,
                           const Eigen::VectorXd& q0,
                           const Eigen::VectorXd& q1);

/// A configuration drawn from a seeded generator: 1-DOF joints uniform inside finite limits
/// (else [-π, π] or [-1, 1] m), rotations uniform on SO(3), free roots within 1 m of the origin.
/// Identical seeds give identical configurations on every platform.
Eigen::VectorXd random_configuration(const Model& model, std::uint64_t seed);

/// Renormalizes every quaternion in q.
void normalize(const Model& model, Eigen::VectorXd& q);

/// Empty when q has size nq, finite entries and unit quaternions (within tol); otherwise a message
/// naming the first offending joint.
std::string check_configuration(const Model& model, const Eigen::VectorXd& q, double tol = 1e-6);

/// Quaternion stored at q[i..i+3] as (w, x, y, z).
inline Quaternion quaternion_at(const Eigen::VectorXd& q, int i) {
  return Quaternion(q[i], q[i + 1], q[i + 2], q[i + 3]);
}
inline void set_quaternion_at(Eigen::VectorXd& q, int i, const Quaternion& r) {
  q[i] = r.w();
  q[i + 1] = r.x();
  q[i + 2] = r.y();
  q[i + 3] = r.z();
}

}  // namespace core
