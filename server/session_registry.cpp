#include "server/session_registry.hpp"

#include <algorithm>
#include <chrono>
#include <iostream>
#include <optional>
#include <system_error>

#include "animator/session_file.hpp"
#include "server/mesh_binary.hpp"
#include "server/security.hpp"

namespace server {

namespace {

constexpr auto kExpiryPeriod = std::chrono::hours(1);

std::int64_t unix_now() {
  return std::chrono::duration_cast<std::chrono::seconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

SessionRegistry::SessionRegistry(RegistryOptions options)
    : options_(std::move(options)),
      pool_(std::make_shared<ActorPool>(options_.actor_threads)),
      store_(options_.data_dir) {
  options_.max_live = std::max<std::size_t>(1, options_.max_live);
  reaper_ = std::thread([this] { reap(); });
}

SessionRegistry::SessionRegistry(std::string data_dir)
    : SessionRegistry(RegistryOptions{.data_dir = std::move(data_dir), .limits = {}}) {}

SessionRegistry::~SessionRegistry() { stop_all(); }

int SessionRegistry::restore(std::ostream& log) {
  std::vector<StoredSession> stored = store_.scan(log);
  int indexed = 0;
  {
    std::lock_guard lock(mutex_);
    for (StoredSession& s : stored) {
      if (entries_.count(s.id)) continue;
      Entry e;
      e.token = std::move(s.token);
      e.character = std::move(s.character);
      e.used_at = s.modified;
      entries_.emplace(s.id, std::move(e));
      ++indexed;
    }
  }
  const int expired = expire();
  if (expired > 0) {
    log << "pindrag serve: deleted " << expired << " sessions untouched for over "
        << options_.expire_days << " days (--expire-days)\n";
  }
  return indexed - expired;
}

// The skinned mesh kept beside a session (<id>.mesh, written once when it was created). A mesh
// that does not read is left out with a line in the log: the session itself is intact.
void SessionRegistry::restore_mesh(const std::string& id, animator::Session& session) const {
  const std::optional<std::string> bytes = store_.read_mesh(id);
  if (!bytes) return;
  try {
    session.set_skin(std::make_shared<const core::SkinnedMesh>(
        decode_mesh_binary(*bytes, session.model().njoints, store_.mesh_path(id))));
  } catch (const std::exception& e) {
    std::cerr << "pindrag serve: session " << id << " opens without its mesh: " << e.what() << "\n";
  }
}

std::shared_ptr<SessionActor> SessionRegistry::load(const std::string& id) {
  const std::string path = store_.session_path(id);
  SessionJournal::Loaded loaded;
  try {
    // the snapshot with the journal's later records replayed; what it drops goes to the log
    loaded = SessionJournal::load(path, std::cerr);
    loaded.session->set_limits(options_.limits);
    restore_mesh(id, *loaded.session);
  } catch (const std::exception& e) {
    throw std::runtime_error("session " + id + ": its saved file does not load: " + e.what());
  }
  store_.touch(id);
  return std::make_shared<SessionActor>(id, std::move(loaded.session), std::move(loaded.journal),
                                        pool_);
}

// Called with the lock held before a session becomes live: when max_live sessions are live (or
// loading), the least recently used one that nobody holds leaves memory.
void SessionRegistry::make_room(std::unique_lock<std::mutex>&) {
  std::size_t live = 0;
  Map::iterator victim = entries_.end();
  for (auto it = entries_.begin(); it != entries_.end(); ++it) {
    const Entry& e = it->second;
    if (e.state == State::kLive || e.state == State::kLoading) ++live;
    // only the registry holds it: no connection, no request, and nobody can take it meanwhile
    // (handing out a reference needs this lock)
    const bool idle = e.state == State::kLive && e.actor.use_count() == 1;
    if (idle && (victim == entries_.end() || e.last_used < victim->second.last_used)) victim = it;
  }
  if (live < options_.max_live) return;
  if (!store_.persistent()) {
    throw SessionsBusy("the server holds " + std::to_string(options_.max_live) +
                       " sessions in memory and has no data directory to move idle ones to "
                       "(rule: --max-live-sessions, or --data-dir)");
  }
  if (victim == entries_.end()) {
    throw SessionsBusy("all " + std::to_string(options_.max_live) +
                       " live sessions are in use by open pages or requests (rule: at most "
                       "--max-live-sessions in memory); retry when one closes");
  }
  victim->second.state = State::kStopping;
  evictions_.push_back(Eviction{victim->first, std::move(victim->second.actor)});
  victim->second.actor.reset();
  changed_.notify_all();
}

SessionHandle SessionRegistry::create(std::unique_ptr<animator::Session> session) {
  session->set_limits(options_.limits);
  SessionHandle handle{random_hex(16), random_hex(16), nullptr};
  {
    std::unique_lock lock(mutex_);
    if (stopping_) throw animator::SessionError("the server is shutting down");
    make_room(lock);
    Entry e;
    e.token = handle.token;
    e.character = session->character();
    e.state = State::kLoading;
    e.used_at = unix_now();
    entries_.emplace(handle.id, std::move(e));
  }
  try {
    const std::string path = store_.session_path(handle.id);
    try {
      store_.write_token(handle.id, handle.token);
      if (session->skin()) store_.write_mesh(handle.id, encode_mesh_binary(*session->skin()));
    } catch (const std::system_error& e) {
      throw animator::SessionWriteError(e.code().value(), e.what());
    }
    // the snapshot and an empty journal are written before the session is announced
    handle.actor = std::make_shared<SessionActor>(handle.id, std::move(session), path, pool_);
  } catch (...) {
    try {
      store_.remove(handle.id);
    } catch (const std::exception&) {
      // the files that stay behind have no session file, so no scan picks them up
    }
    std::lock_guard lock(mutex_);
    entries_.erase(handle.id);
    changed_.notify_all();
    throw;
  }
  std::lock_guard lock(mutex_);
  Entry& e = entries_.at(handle.id);
  e.state = State::kLive;
  e.actor = handle.actor;
  e.last_used = ++use_clock_;
  changed_.notify_all();
  return handle;
}

SessionLookup SessionRegistry::find(std::string_view id, std::string_view token) {
  std::unique_lock lock(mutex_);
  for (;;) {
    const auto it = entries_.find(id);
    if (it == entries_.end()) return {404, nullptr};
    Entry& e = it->second;
    if (!tokens_equal(e.token, token)) return {401, nullptr};
    if (e.state == State::kLive) {
      e.last_used = ++use_clock_;
      e.used_at = unix_now();
      return {200, e.actor};
    }
    if (e.state != State::kStored) {
      changed_.wait(lock);  // being loaded or stopped by another thread: ask again after
      continue;
    }
    if (stopping_) throw animator::SessionError("the server is shutting down");
    make_room(lock);
    e.state = State::kLoading;
    const std::string key(id);
    lock.unlock();
    std::shared_ptr<SessionActor> actor;
    std::exception_ptr error;
    try {
      actor = load(key);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    Entry& loaded = entries_.at(key);  // an entry is never erased while it loads
    loaded.state = actor ? State::kLive : State::kStored;
    loaded.actor = actor;
    loaded.last_used = ++use_clock_;
    loaded.used_at = unix_now();
    changed_.notify_all();
    if (error) std::rethrow_exception(error);
    return {200, actor};
  }
}

int SessionRegistry::remove(std::string_view id, std::string_view token) {
  std::unique_lock lock(mutex_);
  for (;;) {
    const auto it = entries_.find(id);
    if (it == entries_.end()) return 404;
    Entry& e = it->second;
    if (!tokens_equal(e.token, token)) return 401;
    if (e.state == State::kLoading || e.state == State::kStopping) {
      changed_.wait(lock);
      continue;
    }
    if (e.state == State::kLive && e.actor.use_count() > 1) return 409;
    std::shared_ptr<SessionActor> actor = std::move(e.actor);
    e.actor.reset();
    e.state = State::kStopping;
    const std::string key(id);
    lock.unlock();
    if (actor) actor->stop();  // it may still save: delete the files after it has
    actor.reset();
    std::exception_ptr error;
    try {
      store_.remove(key);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error) {
      entries_.at(key).state = State::kStored;
    } else {
      entries_.erase(key);
    }
    changed_.notify_all();
    if (error) std::rethrow_exception(error);
    return 200;
  }
}

std::vector<SessionInfo> SessionRegistry::list() const {
  std::vector<StoredSession> stored;
  std::vector<SessionInfo> out;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, e] : entries_) {
      stored.push_back(StoredSession{.id = id});
      out.push_back(SessionInfo{.id = id,
                                .character = e.character,
                                .modified = e.used_at,
                                .live = e.state == State::kLive});
    }
  }
  store_.stat(stored);
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].bytes = stored[i].bytes;
    out[i].modified = std::max(out[i].modified, stored[i].modified);
  }
  std::stable_sort(out.begin(), out.end(), [](const SessionInfo& a, const SessionInfo& b) {
    return a.modified > b.modified;
  });
  return out;
}

int SessionRegistry::expire() {
  if (options_.expire_days <= 0 || !store_.persistent()) return 0;
  const std::int64_t cutoff = unix_now() - std::int64_t{options_.expire_days} * 86400;
  std::vector<StoredSession> candidates;
  {
    std::lock_guard lock(mutex_);
    for (const auto& [id, e] : entries_) {
      if (e.state == State::kStored && e.used_at < cutoff)
        candidates.push_back(StoredSession{.id = id});
    }
  }
  store_.stat(candidates);
  int removed = 0;
  for (const StoredSession& c : candidates) {
    if (c.modified >= cutoff) continue;
    std::lock_guard lock(mutex_);  // held while deleting: nobody loads it meanwhile
    const auto it = entries_.find(c.id);
    if (it == entries_.end() || it->second.state != State::kStored ||
        it->second.used_at >= cutoff) {
      continue;
    }
    try {
      store_.remove(c.id);
    } catch (const std::exception&) {
      continue;  // tried again at the next expiry
    }
    entries_.erase(it);
    ++removed;
  }
  return removed;
}

void SessionRegistry::reap() {
  std::unique_lock lock(mutex_);
  auto next_expiry = std::chrono::steady_clock::now() + kExpiryPeriod;
  for (;;) {
    changed_.wait_until(lock, next_expiry, [&] { return stopping_ || !evictions_.empty(); });
    if (!evictions_.empty()) {
      Eviction eviction = std::move(evictions_.front());
      evictions_.pop_front();
      lock.unlock();
      eviction.actor->stop();  // runs what was posted to it and keeps its last state
      eviction.actor.reset();
      store_.touch(eviction.id);
      lock.lock();
      const auto it = entries_.find(eviction.id);
      if (it != entries_.end()) it->second.state = State::kStored;
      changed_.notify_all();
      continue;
    }
    if (stopping_) return;
    if (std::chrono::steady_clock::now() >= next_expiry) {
      lock.unlock();
      expire();
      lock.lock();
      next_expiry = std::chrono::steady_clock::now() + kExpiryPeriod;
    }
  }
}

std::size_t SessionRegistry::size() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

std::size_t SessionRegistry::live() const {
  std::lock_guard lock(mutex_);
  return static_cast<std::size_t>(std::count_if(entries_.begin(), entries_.end(), [](auto& kv) {
    return kv.second.state == State::kLive || kv.second.state == State::kLoading;
  }));
}

void SessionRegistry::stop_all() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  if (reaper_.joinable()) reaper_.join();
  std::vector<std::shared_ptr<SessionActor>> actors;
  {
    std::lock_guard lock(mutex_);
    for (auto& [id, e] : entries_) {
      if (e.actor) actors.push_back(e.actor);
    }
  }
  for (auto& actor : actors) actor->stop();
}

}  // namespace server
