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

  // computed by compute_joint_jacobians; rows [angular; linear]
  Matrix6X J;  // joint motion axes in world axes, referenced at the world origin     (6 x nv)

  // computed by center_of_mass
  double mass = 0;                         // total mass
  Vector3 com_W = Vector3::Zero();         // centre of mass in the world
  std::vector<double> subtree_mass;        // mass of the subtree rooted at link i       (njoints)
  std::vector<Vector3> subtree_h_W;        // its first mass moment Σ m c, world         (njoints)
  // computed by com_jacobian
  Matrix3X J_com;                          // d com_W / dv                               (3 x nv)
};

}  // namespace core
