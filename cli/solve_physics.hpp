// The physics path of `pindrag solve`: a request with effects runs in a sim::World instead of the
// kinematic IK solver (docs/ik.md). Its drags, pins and joint references, with dynamic_pins,
// are the body's pin problem (sim/world.hpp); each output frame advances the world by the
// request's dt in fixed physics steps and reports the balance of the figure: centre of mass,
// centre of pressure, support polygon, total normal contact force, the pins' root residual.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "cli/solve_spec.hpp"

namespace cli {

/// Runs `spec` (spec.physics()) and returns its frames; `q` ends as the body's configuration.
/// @throws RequestError when the world refuses the body or its problem
nlohmann::json run_physics(const SolveSpec& spec, Eigen::VectorXd& q);

}  // namespace cli
