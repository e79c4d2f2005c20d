// Centre of mass of the whole figure and its Jacobian.
#pragma once

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Centre of mass in the world; also fills data.mass, data.subtree_mass and data.subtree_h_W.
/// Requires: forward_kinematics(model, data, q).
/// @return data.com_W
const Vector3& center_of_mass(const Model& model, Data& data);

/// COM Jacobian: d com_W / dv. Column k is (M_k v_k + ω_k × h_k) / M, with M_k, h_k the mass and
/// first moment of the subtree moved by coordinate k and [ω_k; v_k] = data.J column k.
/// Requires: compute_joint_jacobians(model, data, q).
/// @return data.J_com (3 x nv)
const Matrix3X& com_jacobian(const Model& model, Data& data);

}  // namespace core
