// `pindrag dynamics FILE --state STATE.json [--fixed-base]`: inverse and forward dynamics, the
// mass matrix and the bias forces of one state, keyed by joint name. Formats: docs/dynamics.md.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/model.hpp"

namespace cli {

/// A state read by joint name: q (nq), v, a, tau (nv). Missing joints are neutral / zero.
struct NamedState {
  Eigen::VectorXd q, v, a, tau;
};

/// Reads {"q": {...}, "v": {...}, "a": {...}, "tau": {...}}: per joint a number (1-DOF), an
/// array [w, x, y, z] in q and 3 numbers in v/a/tau (spherical), [x, y, z, w, qx, qy, qz] in q
/// and 6 numbers [ωx, ωy, ωz, vx, vy, vz] (child frame) in v/a/tau (free).
/// @throws RequestError naming the field (/q/<joint>, /v/<joint>/2, ...) and the rule broken
NamedState read_named_state(const core::Model& model, const nlohmann::json& state);

/// Velocity coordinate names in order: "joint" for 1-DOF joints, "joint[k]" otherwise.
std::vector<std::string> velocity_names(const core::Model& model);

/// Runs the dynamics of one state and returns {"character", "fixed_base", "nq", "nv", "order",
/// "tau" (RNEA for the given a), "a" (ABA for the given tau), "M" (rows in "order"), "bias"}.
/// tau, a and bias are keyed by joint name like the input.
/// @throws RequestError naming the field when the state is bad
nlohmann::json run_dynamics(const core::Model& model, const nlohmann::json& state);

}  // namespace cli
