// Data: the workspace of one model, sized once. Every stage function writes its results here
// (grouped below by the function that writes them) and allocates nothing afterwards.
#pragma once

#include <vector>

#include "core/model.hpp"
#include "core/spatial.hpp"

namespace core {

using Matrix6X = Eigen::Matrix<double, 6, Eigen::Dynamic>;
using Matrix3X = Eigen::Matrix<double, 3, Eigen::Dynamic>;

struct Data {
  explicit Data(const Model& model);

  // computed by forward_kinematics(q)
  std::vector<Transform> X_P;  // pose of link i in its parent link                 (njoints)
  std::vector<Transform> X_W;  // pose of link i in the world; X_W[0] = identity     (njoints)

  // computed by forward_kinematics(q, v) and (q, v, a); link-frame coordinates [ω; v]
  std::vector<Motion> v;       // spatial velocity of link i                         (njoints)
  std::vector<Motion> a_bias;  // spatial acceleration at zero joint acceleration: J̇v (njoints)
  std::vector<Motion> a;       // spatial acceleration for the given joint acceleration (njoints)

  // computed by rnea; link-frame coordinates
  std::vector<Force> f;  // force transmitted through joint i onto link i's subtree (njoints)
  Eigen::VectorXd tau;   // joint forces                                         (nv)

  // computed by crba; world axes, referenced at the world origin. crba keeps its own poses and
  // joint axes (the values of X_W and J for its q) so a caller's X_W and J stay untouched.
  std::vector<SpatialInertia> Ic;   // composite inertia of the subtree of i            (njoints)
  std::vector<Transform> crba_X_W;  // pose of link i in the world                      (njoints)
  Matrix6X crba_S;                  // joint motion axes, as J                          (6 x nv)
  Eigen::MatrixXd crba_F;           // row c: (Ic S_c)ᵀ, Ic the composite of c's joint  (nv x 6)
  Eigen::MatrixXd M;                // joint-space inertia H(q), symmetric              (nv x nv)

  // computed by factorize_mass_matrix: H = Lᵀ D L with the tree's sparsity (RBDA §6.5)
  Eigen::MatrixXd LTDL;  // strictly lower part holds L (unit diagonal), diagonal holds D (nv x nv)

  // computed by aba (RBDA Table 7.1); link-frame coordinates
  std::vector<Matrix6> IA;  // articulated-body inertia                             (njoints)
  std::vector<Force> pA;    // articulated-body bias force                          (njoints)
  std::vector<Motion> c;    // velocity-product acceleration v_i × S_i q̇_i          (njoints)
  std::vector<Eigen::Matrix<double, 6, 6>> U;     // IA S, first nv_i columns        (njoints)
  std::vector<Eigen::Matrix<double, 6, 6>> Dinv;  // (Sᵀ IA S)⁻¹, top-left nv_i block (njoints)
  std::vector<Vector6> u;                         // τ − Sᵀ pA, first nv_i entries    (njoints)
  Eigen::VectorXd ddq;  // joint accelerations                                  (nv)

  // computed by compute_joint_jacobians; rows [angular; linear]
  Matrix6X J;  // joint motion axes in world axes, referenced at the world origin     (6 x nv)

  // computed by center_of_mass
  double mass = 0;                   // total mass
  Vector3 com_W = Vector3::Zero();   // centre of mass in the world
  std::vector<double> subtree_mass;  // mass of the subtree rooted at link i       (njoints)
  std::vector<Vector3> subtree_h_W;  // its first mass moment Σ m c, world         (njoints)
  // computed by centroidal_momentum_matrix
  std::vector<SpatialInertia> Ic_W;  // composite inertia of the subtree of i, world frame (njoints)
  Matrix6X Ag;                       // centroidal momentum matrix: h_G = Ag v            (6 x nv)
  // computed by com_jacobian
  Matrix3X J_com;  // d com_W / dv                               (3 x nv)
};

}  // namespace core
