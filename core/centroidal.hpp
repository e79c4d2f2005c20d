// Centroidal momentum, and kinetic and potential energy of the figure.
#pragma once

#include <Eigen/Core>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Centroidal momentum matrix Ag: h_G = Ag v is the figure's momentum [angular about the COM;
/// linear], world axes (Orin & Goswami 2008). Column k is the world composite inertia of the
/// subtree moved by coordinate k times that coordinate's motion axis, shifted to the COM.
/// Requires: compute_joint_jacobians(model, data, q).
/// @return data.Ag (6 x nv); also fills data.Ic_W and the centre of mass
const Matrix6X& centroidal_momentum_matrix(const Model& model, Data& data);

/// h_G = [angular momentum about the COM; linear momentum], world axes.
/// Requires: forward_kinematics(model, data, q, v).
Force centroidal_momentum(const Model& model, Data& data);

/// ½ vᵀ H v = ½ Σ v_iᵀ I_i v_i. Requires: forward_kinematics(model, data, q, v).
double kinetic_energy(const Model& model, const Data& data);

/// −Σ m_i g · c_i (zero at the world origin). Requires: forward_kinematics(model, data, q).
double potential_energy(const Model& model, const Data& data);

}  // namespace core
