// Placing a character on the ground: its free root moved along the ground normal until the
// lowest point of its collision shapes touches the plane.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/model.hpp"
#include "sim/environment.hpp"

namespace sim {

/// Signed height of the lowest collision point above the plane for configuration q (m); +inf
/// when the model has no collision shape.
double lowest_point_height(const core::Model& model,
                           const Eigen::VectorXd& q,
                           const GroundPlane& ground);

/// q with the free root shifted along the ground normal so the lowest collision point lies
/// `depth` below the plane (0: touching). q itself when the root is not a free joint or the
/// model has no collision shape.
Eigen::VectorXd place_on_ground(const core::Model& model,
                                const Eigen::VectorXd& q,
                                const GroundPlane& ground,
                                double depth = 0);

/// A configuration that stands on the ground: every box-shaped link whose lowest point is within
/// `reach` of the lowest collision point (feet, toes) turned so that its face nearest the ground
/// lies flat on it — spherical joints take the exact turn, revolute joints the turn about their
/// axis that comes closest, within their limits — then placed on the ground (place_on_ground).
/// Links are levelled parents first, so a toe follows its foot.
Eigen::VectorXd standing_configuration(const core::Model& model,
                                       const Eigen::VectorXd& q,
                                       const GroundPlane& ground,
                                       double reach = 0.05);

/// The links a figure in configuration q stands on: those whose lowest collision point is within
/// `reach` of the plane, without the ones whose parent is among them (a toe goes with its foot).
std::vector<int> supporting_links(const core::Model& model,
                                  const Eigen::VectorXd& q,
                                  const GroundPlane& ground,
                                  double reach = 0.005);

}  // namespace sim
