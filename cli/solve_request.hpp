// `pindrag solve --request REQ.json`: run the IK solver headless for a number of frames.
// The request and output formats are documented in docs/ik.md.
#pragma once

#include <nlohmann/json.hpp>

namespace cli {

/// Runs a parsed request and returns the output document.
/// @throws RequestError naming the field when the request is bad (the pose is never touched)
nlohmann::json run_solve_request(const nlohmann::json& request);

}  // namespace cli
