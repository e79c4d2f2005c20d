// The sessions of a server, by id: a bounded cache of live sessions (each an actor with its
// thread) over the sessions saved in the data directory (SessionStore). Any number of sessions
// may be stored; at most `max_live` are in memory. When another one is needed, the least
// recently used idle session (one nobody holds: no WebSocket, no request in flight) is stopped
// (it saves its last state) and leaves memory; it comes back from disk (its snapshot with the
// journal replayed, server/session_journal.hpp) the next time it is found. Sessions untouched for
// `expire_days` are deleted (off by default). Without a data directory there is nothing to come
// back from, so nothing leaves memory: `max_live` is then the number of sessions the server holds.
//
// Thread contract: every function may be called from any thread. One mutex guards the index;
// loading, saving and stopping happen outside it, and a session being loaded or stopped is
// waited for by anyone who asks for it meanwhile. Evicted actors are stopped on the registry's
// own thread, which also runs the expiry once an hour.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "animator/session.hpp"
#include "server/actor_pool.hpp"
#include "server/session_actor.hpp"
#include "server/session_store.hpp"

namespace server {

/// Every live session is in use (held by a connection or a request), so none can make room for
/// another: a temporary refusal (HTTP 503 with Retry-After). (Without a data directory, where
/// sessions cannot leave memory, a full registry refuses so too.)
class SessionsBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RegistryOptions {
  static constexpr std::size_t kDefaultMaxLive = 64;
  std::string data_dir;                    // empty: sessions live in memory only
  std::size_t max_live = kDefaultMaxLive;  // sessions in memory at once (at least 1)
  int expire_days = 0;                     // > 0: delete sessions untouched for that many days
  unsigned actor_threads = 0;              // workers running the sessions' actors; 0: one per core
  animator::Limits limits{};               // every session created or loaded is held to these
};

struct SessionHandle {
  std::string id;
  std::string token;
  std::shared_ptr<SessionActor> actor;
};

/// Outcome of a lookup or removal: the HTTP status it maps to (200, 401, 404; 409 for removing
/// a session in use).
struct SessionLookup {
  int status = 404;
  std::shared_ptr<SessionActor> actor;
};

/// A row of the session list.
struct SessionInfo {
  std::string id;
  std::string character;
  std::int64_t modified = 0;  // Unix seconds: last save or use
  std::uintmax_t bytes = 0;   // on disk
  bool live = false;          // in memory now
};

class SessionRegistry {
 public:
  explicit SessionRegistry(RegistryOptions options);
  explicit SessionRegistry(std::string data_dir);
  ~SessionRegistry();
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

  /// Indexes the saved sessions of the data directory (none is loaded until it is asked for),
  /// deletes the expired ones, reports files it skips to `log`. Returns how many it indexed.
  int restore(std::ostream& log);
  /// Saves a new session (its snapshot, an empty journal and its token) and makes it live.
  /// @throws SessionsBusy, animator::SessionWriteError when it cannot be saved
  SessionHandle create(std::unique_ptr<animator::Session> session);
  /// The session `id` if `token` is its token (compared in constant time), loaded from disk when
  /// it is not live. @throws SessionsBusy, animator::SessionError when its file does not load
  SessionLookup find(std::string_view id, std::string_view token);
  /// Deletes the session and its files: 200, 401 (token), 404, 409 (in use by a connection).
  int remove(std::string_view id, std::string_view token);
  /// Every session, newest first.
  std::vector<SessionInfo> list() const;
  /// Deletes the sessions (not live) untouched for expire_days; returns how many.
  int expire();

  /// Stored sessions (live or not).
  std::size_t size() const;
  /// Sessions in memory now.
  std::size_t live() const;
  /// The threads that run the live sessions' actors.
  std::size_t actor_threads() const { return pool_->threads(); }
  /// Stops every actor (each saves its last state) and the registry's thread.
  void stop_all();
  const std::string& data_dir() const { return options_.data_dir; }
  const RegistryOptions& options() const { return options_; }

 private:
  enum class State { kStored, kLoading, kLive, kStopping };
  struct Entry {
    std::string token;
    std::string character;
    State state = State::kStored;
    std::shared_ptr<SessionActor> actor;  // kLive only
    std::uint64_t last_used = 0;          // use counter, for least-recently-used eviction
    std::int64_t used_at = 0;             // Unix seconds of the last use in this process
  };
  struct Eviction {
    std::string id;
    std::shared_ptr<SessionActor> actor;
  };
  using Map = std::map<std::string, Entry, std::less<>>;

  std::shared_ptr<SessionActor> load(const std::string& id);
  void restore_mesh(const std::string& id, animator::Session& session) const;
  void make_room(std::unique_lock<std::mutex>& lock);
  void reap();

  RegistryOptions options_;
  std::shared_ptr<ActorPool> pool_;  // outlives every actor it runs
  SessionStore store_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;  // an entry left kLoading or kStopping, or evictions queued
  Map entries_;
  std::uint64_t use_clock_ = 0;
  std::deque<Eviction> evictions_;
  bool stopping_ = false;
  std::thread reaper_;
};

}  // namespace server
