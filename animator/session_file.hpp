// Saving and loading sessions: one JSON file holding the character (in the native character
// format), the document (pose, pins, keys, clip, layers, settings, scene) and the playback state.
// Saving is atomic (temp file, fsync, rename), so a crash never leaves a half-written session;
// the file is readable by its owner only (0600). A session file can be the snapshot under a
// journal (server/session_journal.hpp): `journal_seq` is then the last record it holds.
#pragma once

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "animator/document_json.hpp"
#include "animator/session.hpp"

namespace animator {

/// Version of the session file format.
constexpr int kSessionFormatVersion = 1;
/// Largest `journal_seq` of a session file (integers above 2^53 do not survive every JSON reader).
constexpr std::int64_t kMaxJournalSeq = std::int64_t{1} << 53;

/// A session that could not be written (disk full, a file size limit, permissions). error() is
/// the errno value.
class SessionWriteError : public SessionError {
 public:
  SessionWriteError(int error, const std::string& what) : SessionError(what), error_(error) {}
  int error() const { return error_; }
  /// The disk, a quota or a file size limit is full (ENOSPC, EDQUOT, EFBIG).
  bool out_of_space() const;

 private:
  int error_;
};

/// What a session file holds, copied out of a Session so that it can be written on another
/// thread (cheap: the model, clips and layers are shared and immutable).
struct SessionImage {
  std::shared_ptr<const core::Model> model;
  std::string character;
  Document document;
  Playback playback;
  std::shared_ptr<const io::BvhLayout> bvh_source;  // Session::bvh_source; null: none
  std::uint64_t journal_seq = 0;  // the last journal record the image holds; 0: none
};
SessionImage session_image(const Session& session);

/// The session as JSON. Without the character it is the document alone (cheap to compare); with
/// it, also the character's BVH source ("bvh_source", absent when it has none).
nlohmann::json session_to_json(const SessionImage& image, bool include_character = true);
nlohmann::json session_to_json(const Session& session, bool include_character = true);

/// @param journal_seq  receives the file's `journal_seq` (0 when absent) unless null
/// @throws SessionError (or core::ModelError for the embedded character) naming the field
std::unique_ptr<Session> session_from_json(const nlohmann::json& j,
                                           const std::string& source,
                                           std::uint64_t* journal_seq = nullptr);

/// Writes atomically (io/atomic_file.hpp), mode 0600: a temp file in the same folder, fsync,
/// then rename over `path`. @throws SessionWriteError naming the path and the step that failed
void save_session(const SessionImage& image, const std::string& path);
void save_session(const Session& session, const std::string& path);
/// Reads a session file (size, nesting and value count capped; duplicate keys refused).
/// @throws SessionError naming the path and the line and column or the field
std::unique_ptr<Session> load_session(const std::string& path,
                                      std::uint64_t* journal_seq = nullptr);

}  // namespace animator
