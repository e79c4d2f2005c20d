// Marker set files for `pindrag fit` (docs/marker-fitting.md); the format and its checks are
// animator::parse_marker_set's (animator/marker_trial.hpp).
#pragma once

#include <string>

#include "animator/marker_trial.hpp"
#include "core/model.hpp"
#include "ik/marker_set.hpp"

namespace cli {

/// Reads and parses a marker set file; unknown keys are warned about on stderr.
/// @throws RequestError "<path>: <field>: <rule>"
ik::MarkerSet read_marker_set_file(const std::string& path, const core::Model& model);

}  // namespace cli
