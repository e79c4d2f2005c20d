// Marker set files for `pindrag fit` (docs/marker-fitting.md):
//   {"markers": {"LASI": {"link": "pelvis", "offset": [x, y, z], "weight": 1}, ...}}
// "offset" (metres, link frame) may be left out: it is then estimated from the static range and
// starts at the link origin. "weight" is optional (default 1). Unknown keys are warned about.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/model.hpp"
#include "ik/marker_set.hpp"

namespace cli {

/// The marker set described by `doc` on `model`'s links.
/// @throws RequestError "<field>: <rule>", e.g. "/markers/LASI/link: no link 'pelvs' in human48"
ik::MarkerSet parse_marker_set(const nlohmann::json& doc, const core::Model& model);

/// Reads and parses a marker set file. @throws RequestError "<path>: <field>: <rule>"
ik::MarkerSet read_marker_set_file(const std::string& path, const core::Model& model);

/// The bundled marker set for the model (characters/markers/cmu41_<model name>.json), or ""
/// when there is none.
std::string bundled_marker_set_path(const core::Model& model);

}  // namespace cli
