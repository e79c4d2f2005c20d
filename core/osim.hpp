// Operational-space inertia: how forces at handles (points or frames on links) map to the
// handles' accelerations (Yamane ch. 9, digest §2.8).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/data.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"

namespace core {

/// A point on a link where forces act and accelerations are measured. A 3-D handle has the
/// linear rows only; a 6-D handle has rows [angular; linear] (world-aligned, at the point).
struct Handle {
  int link = 0;
  Vector3 p_LinkPoint = Vector3::Zero();
  bool with_orientation = false;  // 6-D when true, 3-D otherwise
  int rows() const { return with_orientation ? 6 : 3; }
};

/// Scratch space of the operational-space functions; sized on first use, reused afterwards.
struct OsimWorkspace {
  Eigen::MatrixXd J;                    // stacked handle Jacobian (m x nv)
  Eigen::MatrixXd Y;                    // L⁻ᵀ Jᵀ scaled by D^-1/2 (nv x m)
  Eigen::VectorXd inverse_sqrt_pivots;  // D^-1/2 of H = Lᵀ D L (nv)
};

/// Stacked task Jacobian of the handles, rows in handle order ([angular; linear] for 6-D).
/// Requires: compute_joint_jacobians(model, data, q).
void handle_jacobian(const Model& model,
                     const Data& data,
                     const std::vector<Handle>& handles,
                     Eigen::MatrixXd& J);

/// Extended inverse operational-space inertia Φ = J H⁻¹ Jᵀ for all handle pairs (block ij is
/// Φ_ij), computed with the tree-sparse factorization H = Lᵀ D L as Φ = Zᵀ Z with
/// Z = D^-1/2 L⁻ᵀ Jᵀ: H⁻¹ is never formed, and each column of Z stays on its handle's path.
/// Requires: compute_joint_jacobians and crba with the same q, then factorize_mass_matrix.
void inverse_operational_inertia(const Model& model,
                                 const Data& data,
                                 const std::vector<Handle>& handles,
                                 OsimWorkspace& ws,
                                 Eigen::MatrixXd& Phi);

/// Λ = Φ⁻¹, well defined when Φ is singular: the pseudoinverse over eigenvalues above
/// rel_tol × the largest (directions the handle cannot accelerate get zero inertia). Returns the
/// rank kept.
int operational_inertia(const Eigen::MatrixXd& Phi,
                        Eigen::MatrixXd& Lambda,
                        double rel_tol = 1e-10);

/// The floating-base split of the handle equations (digest §2.8, Yamane ch. 9 standard form):
/// with θ = (θ_b, q) and the root a free joint,
///   r̈_i = Γ_i q̈ + Σ_k Φ^lock_ik f_k + ψ_i,
///   Γ = J_q − J_b H_bb⁻¹ H_bq,  Φ^lock = J_b H_bb⁻¹ J_bᵀ,  ψ = J̇ v − J_b H_bb⁻¹ b_b.
/// It also keeps floating_base_split's scratch space, so a call with the same handles reuses it.
struct FloatingBaseSplit {
  Eigen::Matrix<double, 6, 6> H_bb;  // whole-body composite rigid-body inertia (root frame)
  Eigen::MatrixXd Gamma;             // (m x (nv − 6))
  Eigen::MatrixXd Phi_lock;          // (m x m)
  Eigen::VectorXd psi;               // (m)
  // scratch, reused by the next call with as many handle rows
  Eigen::MatrixXd J;    // stacked handle Jacobian [J_b J_q] (m x nv)
  Eigen::MatrixXd J_b;  // its root columns (m x 6)
  Eigen::MatrixXd X;    // J_b H_bb⁻¹ (m x 6)
  // H_bb⁻¹ J_bᵀ (6 x m), row-major like the right-hand side J_bᵀ
  Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::RowMajor> X_t;
};

/// Requires: a free root; crba, bias forces in data.tau (bias_forces), compute_joint_jacobians
/// and forward_kinematics(q, v) for J̇v, all with the same q (and v).
/// Allocation-free once `out` has been used with handles of the same row count.
void floating_base_split(const Model& model,
                         const Data& data,
                         const std::vector<Handle>& handles,
                         const Eigen::VectorXd& bias,
                         FloatingBaseSplit& out);

}  // namespace core
