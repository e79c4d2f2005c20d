#include "server/session_registry.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "animator/session_file.hpp"
#include "server/security.hpp"

namespace server {
namespace fs = std::filesystem;

namespace {

// The token file is readable by the owner only: it is the key to the session.
void write_token(const std::string& path, const std::string& token) {
  const std::string temp = path + ".tmp";
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), temp);
  const bool ok = ::write(fd, token.data(), token.size()) == static_cast<ssize_t>(token.size()) &&
                  ::fsync(fd) == 0;
  ::close(fd);
  if (!ok || ::rename(temp.c_str(), path.c_str()) != 0) {
    throw std::system_error(errno, std::generic_category(), path);
  }
}

}  // namespace

SessionRegistry::SessionRegistry(std::string data_dir, animator::Limits limits)
    : data_dir_(std::move(data_dir)), limits_(limits) {
  if (!data_dir_.empty()) fs::create_directories(fs::path(data_dir_) / "sessions");
}

SessionRegistry::~SessionRegistry() { stop_all(); }

std::string SessionRegistry::session_path(const std::string& id) const {
  if (data_dir_.empty()) return {};
  return (fs::path(data_dir_) / "sessions" / (id + ".json")).string();
}

int SessionRegistry::restore(std::ostream& log) {
  if (data_dir_.empty()) return 0;
  int restored = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(data_dir_) / "sessions")) {
    const fs::path path = entry.path();
    if (path.extension() != ".json" || !is_valid_id(path.stem().string())) continue;
    const std::string id = path.stem().string();
    try {
      std::ifstream token_file(fs::path(path).replace_extension(".token"));
      std::string token;
      if (!(token_file >> token) || !is_valid_id(token)) {
        throw std::runtime_error("missing or malformed token file");
      }
      auto session = animator::load_session(path.string());
      session->set_limits(limits_);
      auto actor = std::make_shared<SessionActor>(id, std::move(session), path.string());
      std::lock_guard lock(mutex_);
      if (sessions_.size() >= kMaxSessions)
        throw TooManySessions("more saved sessions than the server holds");
      sessions_[id] = SessionHandle{id, token, std::move(actor)};
      ++restored;
    } catch (const std::exception& e) {
      log << "pindrag serve: session " << path.string() << " not restored: " << e.what() << "\n";
    }
  }
  return restored;
}

SessionHandle SessionRegistry::create(std::unique_ptr<animator::Session> session) {
  {
    std::lock_guard lock(mutex_);
    if (sessions_.size() >= kMaxSessions) {
      throw TooManySessions("the server holds " + std::to_string(kMaxSessions) +
                            " sessions already");
    }
  }
  session->set_limits(limits_);
  SessionHandle handle{random_hex(16), random_hex(16), nullptr};
  const std::string path = session_path(handle.id);
  if (!path.empty()) {
    write_token((fs::path(path).replace_extension(".token")).string(), handle.token);
    animator::save_session(*session, path);
  }
  handle.actor = std::make_shared<SessionActor>(handle.id, std::move(session), path);
  std::lock_guard lock(mutex_);
  sessions_[handle.id] = handle;
  return handle;
}

SessionLookup SessionRegistry::find(std::string_view id, std::string_view token) const {
  std::lock_guard lock(mutex_);
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return {404, nullptr};
  if (!tokens_equal(it->second.token, token)) return {401, nullptr};
  return {200, it->second.actor};
}

std::size_t SessionRegistry::size() const {
  std::lock_guard lock(mutex_);
  return sessions_.size();
}

void SessionRegistry::stop_all() {
  std::map<std::string, SessionHandle, std::less<>> sessions;
  {
    std::lock_guard lock(mutex_);
    sessions = sessions_;
  }
  for (auto& entry : sessions) entry.second.actor->stop();
}

}  // namespace server
