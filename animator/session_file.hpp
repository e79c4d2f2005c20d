// Saving and loading sessions: one JSON file holding the character (in the native character
// format), the document (pose, pins, keys, clip, layers, settings, scene) and the playback state.
// Saving is atomic (temp file, fsync, rename), so a crash never leaves a half-written session.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "animator/session.hpp"

namespace animator {

/// Version of the session file format.
constexpr int kSessionFormatVersion = 1;

/// The session as JSON. Without the character it is the document alone (cheap to compare).
nlohmann::json session_to_json(const Session& session, bool include_character = true);

/// @throws SessionError (or core::ModelError for the embedded character) naming the field
std::unique_ptr<Session> session_from_json(const nlohmann::json& j, const std::string& source);

/// Writes atomically (io/atomic_file.hpp): a temp file in the same folder, fsync, then rename
/// over `path`. @throws SessionError naming the path and the step that failed
void save_session(const Session& session, const std::string& path);
/// Reads a session file (size, nesting and value count capped; duplicate keys refused).
/// @throws SessionError naming the path and the line and column or the field
std::unique_ptr<Session> load_session(const std::string& path);

/// The settings as JSON and back (also used by the wire protocol of the server).
nlohmann::json settings_to_json(const ik::SolverSettings& s);
/// The scene as {"gravity": bool, ...}: every effect of sim::kAllEffects by name.
nlohmann::json scene_to_json(const sim::Scene& scene);
/// Applies the keys present in j to `s`; unknown keys and bad values raise SessionError.
void settings_from_json(const nlohmann::json& j, ik::SolverSettings& s);

}  // namespace animator
