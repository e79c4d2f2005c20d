// Articulated-body algorithm: forward dynamics in O(n).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Forward dynamics a = FD(q, v, τ) = H⁻¹(τ − b), with gravity model.gravity. RBDA Table 7.1,
/// generalized to multi-DOF joints; cross-checked against crba()/rnea() in
/// tests/core/dynamics_test.cpp (Aba.InvertsRnea, Aba.EqualsInverseInertiaTimesTauMinusBias).
/// @return data.ddq (nv)
const Eigen::VectorXd& aba(const Model& model,
                           Data& data,
                           const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v,
                           const Eigen::VectorXd& tau);

/// The same with external forces f_ext[i] on link i, in link i's frame (njoints entries).
const Eigen::VectorXd& aba(const Model& model,
                           Data& data,
                           const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v,
                           const Eigen::VectorXd& tau,
                           const std::vector<Force>& f_ext);

}  // namespace core
