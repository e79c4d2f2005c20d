// The sessions saved in a data directory, as files: <dir>/sessions/<id>.json (the session),
// <id>.token beside it (its token, mode 0600), and whatever other <id>.* files the session's
// actor keeps; deleting a session removes them all. File operations only: no actors and no
// locks (SessionRegistry serializes the work on one id).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace server {

/// One saved session as the store sees it.
struct StoredSession {
  std::string id{};
  std::string token{};
  std::string character{};    // the character's name, "" when the file does not say
  std::int64_t modified = 0;  // newest change or use of any of its files, Unix seconds
  std::uintmax_t bytes = 0;   // all its files together
};

class SessionStore {
 public:
  /// `data_dir` empty: a store that holds nothing (sessions live in memory only).
  explicit SessionStore(std::string data_dir);

  bool persistent() const { return !dir_.empty(); }
  /// <dir>/sessions/<id>.json, or "" when not persistent.
  std::string session_path(const std::string& id) const;

  /// Every saved session with a well-formed id and token; each file it skips is reported to
  /// `log` with the reason. Reads only the head of each session file (the character's name).
  std::vector<StoredSession> scan(std::ostream& log) const;
  /// Writes <id>.token (0600, fsync'd, renamed into place).
  /// @throws std::system_error naming the file
  void write_token(const std::string& id, const std::string& token) const;
  /// Fills `modified` and `bytes` of each session from its files (one pass over the folder).
  void stat(std::vector<StoredSession>& sessions) const;
  /// Marks the session as used now (the token file's time), so expiry spares it.
  void touch(const std::string& id) const;
  /// <dir>/sessions/<id>.mesh: the character's skinned mesh (server/mesh_binary.hpp), written
  /// once when the session is created; "" when not persistent.
  std::string mesh_path(const std::string& id) const;
  /// Writes <id>.mesh (0600, atomically). @throws std::system_error naming the file
  void write_mesh(const std::string& id, const std::string& bytes) const;
  /// The bytes of <id>.mesh; empty when there is none (or no store).
  std::optional<std::string> read_mesh(const std::string& id) const;
  /// Deletes every file of the session. @throws std::system_error naming the file
  void remove(const std::string& id) const;

 private:
  std::string dir_;  // <data_dir>/sessions, or ""
};

/// The value of the top-level "character_name" of a session file, read without building the
/// document (it stops there); "" when absent or unreadable.
std::string session_character_name(const std::string& path);

/// Writes a secret `text` to `path` readable by the owner only (0600), atomically.
/// @throws std::system_error naming the file
void write_private_file(const std::string& path, const std::string& text);

}  // namespace server
