// The difference between two states of a session (document and playback) as JSON, and its
// application: what one journal record holds (server/session_journal.hpp). Replaying changes
// reproduces the later state bit for bit, whatever produced it (an edit, the solver settling,
// undo), without running the solver again.
//
// Only what differs is written, in the session file's notation (document_json.hpp):
//   {"q": [...], "pins": [...], "clip": {...} | null, "markers": {...} | null,
//    "settings": {...}, "scene": {...},
//    "edit_falloff": s, "playback": {...},
//    "keys":   {"at": i, "remove": n, "insert": [key, ...]},
//    "layers": {"at": i, "remove": n, "insert": [layer, ...]}}
// Keys and layers are spliced: the n entries from index i are replaced by those inserted, so a
// key edit writes one key, not the track. Layers and clips are shared and immutable, so they
// compare by identity and only new ones are written.
#pragma once

#include <nlohmann/json.hpp>

#include "animator/document.hpp"
#include "animator/session.hpp"

namespace animator {

/// The changes from (`doc0`, `playback0`) to (`doc1`, `playback1`) of a session of `model`;
/// an empty object when nothing saved differs (whether it plays is not saved).
nlohmann::json document_changes(const core::Model& model,
                                const Document& doc0,
                                const Playback& playback0,
                                const Document& doc1,
                                const Playback& playback1);

/// Applies changes written by document_changes to `doc` and `playback`, which are left as
/// they were when it throws. @throws SessionError naming the field ("/keys/insert/0/q: ...")
void apply_document_changes(const core::Model& model,
                            const nlohmann::json& changes,
                            Document& doc,
                            Playback& playback);

}  // namespace animator
