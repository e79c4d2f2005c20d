// The parts of a session's document and playback state as JSON, and read back with errors that
// name the field: shared by the session file (session_file.hpp) and the changes a journal
// record holds (document_changes.hpp). Values are kept bit for bit: doubles are written in
// shortest round-trip form, saved quaternions are checked to be unit, not renormalized.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "animator/document.hpp"
#include "animator/session.hpp"
#include "io/bvh_import.hpp"
#include "io/json_parse.hpp"
#include "io/json_reader.hpp"

namespace animator {

/// Caps of a session file or a journal record. Sessions embed a character (up to 64 MiB) and
/// clips and edit layers of any length; the caps only keep a damaged or hostile file from
/// costing unbounded memory.
constexpr io::JsonLimits kSessionJsonLimits{.max_bytes = std::size_t{1} << 30,
                                            .max_depth = io::kMaxJsonDepth,
                                            .max_values = std::size_t{1} << 27};

/// The settings as JSON and back (also used by the wire protocol of the server).
nlohmann::json settings_to_json(const ik::SolverSettings& s);
/// Applies the keys present in j to `s`; unknown keys and bad values raise SessionError.
void settings_from_json(const nlohmann::json& j, ik::SolverSettings& s);
/// The keys present in `j` over `s` (any error names the field).
void read_settings(io::JsonFields& f, const io::JsonField& j, ik::SolverSettings& s);

nlohmann::json configuration_to_json(const Eigen::VectorXd& q);
/// nq numbers that pass core::check_configuration.
Eigen::VectorXd read_configuration(io::JsonFields& f, const io::JsonField& q, const core::Model& m);

nlohmann::json pins_to_json(const core::Model& m, const std::vector<Pin>& pins);
std::vector<Pin> read_pins(io::JsonFields& f, const io::JsonField& pins, const core::Model& m);

nlohmann::json key_to_json(const Keyframe& k);
Keyframe read_key(io::JsonFields& f, const io::JsonField& key, const core::Model& m);

nlohmann::json layer_to_json(const EditLayer& l);
std::shared_ptr<const EditLayer> read_layer(io::JsonFields& f,
                                            const io::JsonField& layer,
                                            const core::Model& m);

nlohmann::json clip_to_json(const core::Clip& c);
/// A clip that passes core::check_clip for `m`.
std::shared_ptr<const core::Clip> read_clip(io::JsonFields& f,
                                            const io::JsonField& clip,
                                            const core::Model& m);

/// The markers of a clip's trial as {"rate": Hz, "markers": [{"name", "link", "offset": [x, y,
/// z]}], "frames": [[x, y, z, x, y, z, ...], ...]}: one row per frame, three numbers per marker in
/// the order of "markers", null for each coordinate of a missing sample (metres, world frame).
nlohmann::json clip_markers_to_json(const core::Model& m, const ClipMarkers& markers);
/// Markers that pass check_clip_markers for `m` (a fresh revision).
std::shared_ptr<const ClipMarkers> read_clip_markers(io::JsonFields& f,
                                                     const io::JsonField& markers,
                                                     const core::Model& m);

/// Empty when the document's markers, if any, ride on its clip (check_markers_fit_clip); else
/// the rule broken.
std::string check_document_markers(const Document& d);

/// The scene as {"gravity": bool, ...}: every effect of sim::kAllEffects by name.
nlohmann::json scene_to_json(const sim::Scene& scene);
sim::Scene read_scene(io::JsonFields& f, const io::JsonField& scene);

/// The BVH file a character came from (Session::bvh_source) as {"scale": metres per file unit,
/// "joints": [{"name": "Hips", "channels": ["Xposition", ..., "Yrotation"]}, ...]} in file order.
nlohmann::json bvh_source_to_json(const io::BvhLayout& layout);
/// A layout with a positive scale, at most io::kMaxBvhJoints joints with distinct names, and at
/// most 6 distinct channels each, named as io::to_string(BvhChannel) writes them.
std::shared_ptr<const io::BvhLayout> read_bvh_source(io::JsonFields& f, const io::JsonField& j);

/// Time, speed and loop; whether it plays is not saved.
nlohmann::json playback_to_json(const Playback& p);
Playback read_playback(io::JsonFields& f, const io::JsonField& playback);

}  // namespace animator
