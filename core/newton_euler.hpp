// The Newton–Euler / D'Alembert formulation of the [NE] paper (digest §2.14): a second, readable
// dynamics path for serial chains of revolute joints in Denavit–Hartenberg frames.
//
// Every link is held in D'Alembert equilibrium under its inertial force F_i = m_i v̇_Ci and moment
// N_i = I_i ω̇_i + ω_i × I_i ω_i, its weight and the actuator torques. Summing the moments of all
// links outboard of joint j about the origin of frame j and projecting on the joint axis gives
// one scalar equation per joint; separating the terms linear in θ̈ gives the paper's ODE
//
//     M(θ) θ̈ = G(θ) − H(θ, θ̇) + τ                                      (NE eq. 9)
//
// so τ = M θ̈ + H − G (inverse problem) and θ̈ = M⁻¹(τ − H + G) (forward problem, NE eq. 13).
// A cross-check path, not a per-step one: tests/core/newton_euler_test.cpp checks it against
// rnea(), crba() and aba(), and nothing in the per-step paths (IK, animation, simulation) calls
// it. It is O(n²) to O(n³) and allocates its results.
//
// Frames follow the paper (Craig's modified DH): frame j sits on link j at joint j, joint j turns
// about its z axis, and the transform from frame j−1 to frame j is
//     ʲ⁻¹T_j = Rot_x(α_{j−1}) · Trans_x(a_{j−1}) · Rot_z(θ_j + offset_j) · Trans_z(d_j).
// Frame 0 is the fixed base; gravity is given in it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/spatial.hpp"

namespace core {

/// Joint j and link j of a DH chain.
struct DhJoint {
  double a = 0;                   // a_{j−1}: distance along x_{j−1} from z_{j−1} to z_j (m)
  double alpha = 0;               // α_{j−1}: angle about x_{j−1} from z_{j−1} to z_j (rad)
  double d = 0;                   // d_j: distance along z_j from x_{j−1} to x_j (m)
  double theta_offset = 0;        // added to the joint variable θ_j (rad)
  double mass = 0;                // m_j (kg)
  Vector3 com = Vector3::Zero();  // P_Cj: centre of mass in frame j (m)
  Matrix3 inertia = Matrix3::Zero();  // I_j about the centre of mass, frame-j axes (kg m²)
};

/// A fixed-base serial chain of revolute joints.
struct DhChain {
  std::vector<DhJoint> joints;
  Vector3 gravity{0, 0, -9.81};  // in base frame {0}
  int size() const { return static_cast<int>(joints.size()); }
};

/// External load on the last link: force F_Q applied at the point P_Q plus a free moment M_Q,
/// acting on the manipulator. NE eqs. 3–5: N_Q = P_Q × F_Q + M_Q enters every joint's moment sum.
struct DhEndLoad {
  Vector3 force_0 = Vector3::Zero();   // F_Q in base frame {0}
  Vector3 point_n = Vector3::Zero();   // P_Q in the last link's frame {n}
  Vector3 moment_0 = Vector3::Zero();  // M_Q in base frame {0}
};

/// Pose of frame j in frame j−1 for joint value θ_j (the DH transform above).
Transform dh_transform(const DhJoint& joint, double theta);

/// Poses of frames 1..n in the base frame (entry j−1 is frame j).
std::vector<Transform> dh_forward_kinematics(const DhChain& chain, const Eigen::VectorXd& theta);

/// M(θ): M_jk = Σ_{i ≥ max(j,k)} m_i (z_j × (p_Ci − o_j))·(z_k × (p_Ci − o_k)) + z_jᵀ I_i z_k,
/// the coefficients of θ̈ in the outboard moment sums (NE eqs. 7–9). Symmetric (n x n).
Eigen::MatrixXd dh_mass_matrix(const DhChain& chain, const Eigen::VectorXd& theta);

/// H(θ, θ̇): the velocity terms of the moment sums, evaluated with θ̈ = 0 through the C_ω, C_v,
/// C_vC recursions of NE eq. 8, plus −z_j·N_Q when `load` is given (the load torque enters H with
/// the sign that makes τ = M θ̈ + H − G hold).
Eigen::VectorXd dh_velocity_terms(const DhChain& chain,
                                  const Eigen::VectorXd& theta,
                                  const Eigen::VectorXd& theta_dot,
                                  const DhEndLoad* load = nullptr);

/// G(θ): G_j = z_j · Σ_{i≥j} (p_Ci − o_j) × m_i g, the moment of the weights about joint j.
Eigen::VectorXd dh_gravity_terms(const DhChain& chain, const Eigen::VectorXd& theta);

/// Inverse problem: τ = M(θ) θ̈ + H(θ, θ̇) − G(θ).
Eigen::VectorXd dh_inverse_dynamics(const DhChain& chain,
                                    const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& theta_dot,
                                    const Eigen::VectorXd& theta_ddot,
                                    const DhEndLoad* load = nullptr);

/// Forward problem (NE eq. 13): θ̈ = M⁻¹(τ − H + G), M factorized by Cholesky.
Eigen::VectorXd dh_forward_dynamics(const DhChain& chain,
                                    const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& theta_dot,
                                    const Eigen::VectorXd& tau,
                                    const DhEndLoad* load = nullptr);

/// The hydraulic joint after a sudden valve closure (NE eq. 14): τ_j = −k_j(θ_j − θ_j0) − d_j θ̇_j.
Eigen::VectorXd valve_closure_torques(const Eigen::VectorXd& stiffness,
                                      const Eigen::VectorXd& damping,
                                      const Eigen::VectorXd& theta_free,
                                      const Eigen::VectorXd& theta,
                                      const Eigen::VectorXd& theta_dot);

}  // namespace core
