// Contact points grouped into pairs, and the wrench each pair exerts over one step.
//
// A pair is one link touching one partner (the environment, or another link of its body); its
// wrench τ acts at the pair's reference point (the mean of its points), world axes, [moment;
// force], on the link, and −τ on a partner link. The pair's coordinates are the link's 6-D
// motion relative to its partner at that point: q̇ = [ω; v], with ṗ_k = v + ω × (p_k − ref) at
// each point (J_k = [−[r_k ×], E], Yamane eqs. 6.21–6.28), so τ = Σ J_kᵀ f_k, K = ∂τ/∂q =
// Σ J_kᵀ F_kp J_k and D = ∂τ/∂q̇ = Σ J_kᵀ F_kd J_k.
//
// The implicit step (Yamane eq. 6.6 applied in contact space, eqs. 6.11–6.13): with Φ the
// pairs' inverse operational inertia and r̂̈ their accelerations without contact, one backward-
// Euler step of q̈ = Φ τ(q, q̇) + r̂̈, linearized around the step's start, gives the wrench
//     (E − h (D + h K) Φ) τ̂ = τ₀ + h K q̇₀ + h (D + h K) r̂̈,
// which is the book's (6.6) solved for τ̂ instead of Δq̇ (so Φ need not be inverted, and links
// whose Φ is singular, as on a fixed-base arm, are fine). All pairs are solved together, so two
// feet of one figure see each other through Φ (the book solves each pair alone).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <vector>

#include "sim/collision.hpp"

namespace sim {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

struct ContactPair {
  int body = 0, link = 0;
  int partner_body = -1, partner_link = 0;  // -1: the environment
  int first_point = 0, point_count = 0;     // into the step's sorted contact points
  core::Vector3 ref_W = core::Vector3::Zero();
  core::Vector3 normal_W = core::Vector3::Zero();  // its points' mean normal, partner toward link
  Vector6 velocity = Vector6::Zero();  // q̇₀: the link's motion relative to its partner at ref
  Vector6 wrench0 = Vector6::Zero();   // τ₀: the explicit wrench at the step's start
  Matrix6 K = Matrix6::Zero();         // ∂τ/∂q
  Matrix6 D = Matrix6::Zero();         // ∂τ/∂q̇
  Vector6 wrench = Vector6::Zero();    // τ̂: the wrench applied over the step
  bool sticking = false;               // static friction held at the step's start
};

/// Sorts the points so that each pair's points are contiguous and fills `pairs` (body, link,
/// partner, points, reference point); the per-step fields are left zero.
void group_into_pairs(std::vector<ContactPoint>& points, std::vector<ContactPair>& pairs);

/// Scratch space of the implicit solve, sized on growth.
struct ImplicitWorkspace {
  Eigen::MatrixXd A;
  Eigen::VectorXd rhs, x;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  std::vector<char> released;  // per pair: let go because it pulled
};

/// The implicit contact solve: `Phi` (6P × 6P) and `free_acceleration` (6P, r̂̈) over all P
/// pairs in order; writes every pair's `wrench`. The linearized step can ask a pair that is
/// coming apart fast to pull; such a pair is let go (its wrench 0) and the others solved again,
/// until none pulls: contacts only push.
void solve_implicit_wrenches(std::vector<ContactPair>& pairs,
                             const Eigen::MatrixXd& Phi,
                             const Eigen::VectorXd& free_acceleration,
                             double h,
                             ImplicitWorkspace& ws);

}  // namespace sim
