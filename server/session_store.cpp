#include "server/session_store.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <system_error>

#include "server/security.hpp"

namespace server {
namespace fs = std::filesystem;

namespace {

// SAX reader that keeps the string value of one top-level key and stops the parse there.
class TopLevelString final : public nlohmann::json_sax<nlohmann::json> {
 public:
  explicit TopLevelString(std::string key) : key_(std::move(key)) {}
  std::string value;

  bool null() override { return scalar(); }
  bool boolean(bool) override { return scalar(); }
  bool number_integer(number_integer_t) override { return scalar(); }
  bool number_unsigned(number_unsigned_t) override { return scalar(); }
  bool number_float(number_float_t, const string_t&) override { return scalar(); }
  bool string(string_t& s) override {
    if (depth_ == 1 && wanted_) {
      value = s;
      return false;  // found: stop reading
    }
    return scalar();
  }
  bool binary(binary_t&) override { return scalar(); }
  bool start_object(std::size_t) override { return open(); }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    wanted_ = depth_ == 1 && k == key_;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  bool scalar() {
    if (depth_ == 1) wanted_ = false;
    return true;
  }
  bool open() {
    if (depth_ == 1) wanted_ = false;
    return ++depth_ < 512;  // the session reader's own nesting cap is far lower
  }
  bool close() {
    --depth_;
    return true;
  }
  std::string key_;
  int depth_ = 0;
  bool wanted_ = false;
};

std::int64_t unix_seconds(fs::file_time_type t) {
  const auto system = std::chrono::time_point_cast<std::chrono::seconds>(
      t - fs::file_time_type::clock::now() + std::chrono::system_clock::now());
  return system.time_since_epoch().count();
}

// "<id>" of "<id>.<anything>" when <id> is a session id, else "".
std::string owner_id(const fs::path& file) {
  const std::string name = file.filename().string();
  const size_t dot = name.find('.');
  if (dot == std::string::npos) return {};
  std::string id = name.substr(0, dot);
  return is_valid_id(id) ? id : std::string();
}

}  // namespace

std::string session_character_name(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  TopLevelString reader("character_name");
  try {
    nlohmann::json::sax_parse(in, &reader);
  } catch (const std::exception&) {
    return {};
  }
  return reader.value;
}

void write_private_file(const std::string& path, const std::string& text) {
  const std::string temp = path + ".tmp";
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), temp);
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size()) &&
                  ::fsync(fd) == 0;
  const int write_errno = errno;
  ::close(fd);
  if (!ok) {
    ::unlink(temp.c_str());
    throw std::system_error(write_errno, std::generic_category(), temp);
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    throw std::system_error(errno, std::generic_category(), path);
  }
}

SessionStore::SessionStore(std::string data_dir) {
  if (data_dir.empty()) return;
  dir_ = (fs::path(data_dir) / "sessions").string();
  fs::create_directories(dir_);
}

std::string SessionStore::session_path(const std::string& id) const {
  if (dir_.empty()) return {};
  return (fs::path(dir_) / (id + ".json")).string();
}

std::vector<StoredSession> SessionStore::scan(std::ostream& log) const {
  std::vector<StoredSession> found;
  if (dir_.empty()) return found;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const fs::path path = entry.path();
    if (path.extension() != ".json" || !is_valid_id(path.stem().string())) continue;
    StoredSession s;
    s.id = path.stem().string();
    std::ifstream token_file(fs::path(path).replace_extension(".token"));
    if (!(token_file >> s.token) || !is_valid_id(s.token)) {
      log << "pindrag serve: session " << path.string()
          << " skipped: missing or malformed token file (rule: " << s.id
          << ".token holds 32 lowercase hex digits)\n";
      continue;
    }
    s.character = session_character_name(path.string());
    found.push_back(std::move(s));
  }
  stat(found);
  return found;
}

void SessionStore::write_token(const std::string& id, const std::string& token) const {
  if (dir_.empty()) return;
  write_private_file((fs::path(dir_) / (id + ".token")).string(), token);
}

void SessionStore::stat(std::vector<StoredSession>& sessions) const {
  if (dir_.empty()) return;
  std::map<std::string, StoredSession*> by_id;
  for (StoredSession& s : sessions) {
    s.bytes = 0;
    s.modified = 0;
    by_id[s.id] = &s;
  }
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    const auto it = by_id.find(owner_id(entry.path()));
    if (it == by_id.end()) continue;
    std::error_code file_ec;
    const auto size = entry.file_size(file_ec);
    if (!file_ec) it->second->bytes += size;
    const auto time = entry.last_write_time(file_ec);
    if (!file_ec) it->second->modified = std::max(it->second->modified, unix_seconds(time));
  }
}

std::string SessionStore::mesh_path(const std::string& id) const {
  if (dir_.empty()) return {};
  return (fs::path(dir_) / (id + ".mesh")).string();
}

void SessionStore::write_mesh(const std::string& id, const std::string& bytes) const {
  if (dir_.empty()) return;
  write_private_file(mesh_path(id), bytes);
}

std::optional<std::string> SessionStore::read_mesh(const std::string& id) const {
  if (dir_.empty()) return std::nullopt;
  std::ifstream f(mesh_path(id), std::ios::binary);
  if (!f) return std::nullopt;
  std::ostringstream bytes;
  bytes << f.rdbuf();
  return bytes.str();
}

void SessionStore::touch(const std::string& id) const {
  if (dir_.empty()) return;
  const std::string path = (fs::path(dir_) / (id + ".token")).string();
  ::utimensat(AT_FDCWD, path.c_str(), nullptr, 0);  // best effort: only expiry reads it
}

void SessionStore::remove(const std::string& id) const {
  if (dir_.empty()) return;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    if (owner_id(entry.path()) == id) files.push_back(entry.path());
  }
  // the session file first: a crash in between leaves only files that no scan looks at
  std::stable_partition(files.begin(), files.end(),
                        [](const fs::path& f) { return f.extension() == ".json"; });
  for (const fs::path& file : files) {
    if (::unlink(file.c_str()) != 0 && errno != ENOENT) {
      throw std::system_error(errno, std::generic_category(), file.string());
    }
  }
}

}  // namespace server
