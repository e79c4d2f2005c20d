// The sessions of a server, by id: created from a character, found by id and token, saved under
// <data-dir>/sessions/<id>.json (with the token beside it, mode 0600) and restored at startup.
// Thread contract: every function may be called from any thread (one mutex over the map).
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "animator/session.hpp"
#include "server/session_actor.hpp"

namespace server {

/// Creation refused because the server holds kMaxSessions sessions already.
class TooManySessions : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SessionHandle {
  std::string id;
  std::string token;
  std::shared_ptr<SessionActor> actor;
};

/// Outcome of a lookup: the HTTP status it maps to (200, 401 or 404).
struct SessionLookup {
  int status = 404;
  std::shared_ptr<SessionActor> actor;
};

class SessionRegistry {
 public:
  static constexpr std::size_t kMaxSessions = 256;

  /// `data_dir` empty: sessions live in memory only. Every session created or restored is held
  /// to `limits` (animator/limits.hpp).
  explicit SessionRegistry(std::string data_dir, animator::Limits limits = {});
  ~SessionRegistry();

  /// Loads every saved session of the data directory; reports each one it cannot load to `log`
  /// and goes on. Returns how many were restored.
  int restore(std::ostream& log);
  /// @throws TooManySessions, std::system_error when the data directory cannot be written
  SessionHandle create(std::unique_ptr<animator::Session> session);
  /// The session `id` if `token` is its token (compared in constant time).
  SessionLookup find(std::string_view id, std::string_view token) const;
  std::size_t size() const;
  /// Stops every actor (each saves its last state).
  void stop_all();
  const std::string& data_dir() const { return data_dir_; }

 private:
  std::string session_path(const std::string& id) const;

  std::string data_dir_;
  animator::Limits limits_;
  mutable std::mutex mutex_;
  std::map<std::string, SessionHandle, std::less<>> sessions_;
};

}  // namespace server
