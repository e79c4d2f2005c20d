// The pindrag server: HTTP (cpp-httplib) on port P and the WebSocket (Boost.Beast) on P+1 over
// one session registry. Binding happens in the constructor, so a port in use is reported at once;
// start() runs both on their own threads; stop() shuts both down and stops every session actor
// (each saves its last state). DESIGN.md §6, docs/protocol.md. HTTP requests wait for a session
// at most call_timeout (then 503); headers arrive within header_timeout or the connection closes.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "server/session_registry.hpp"
#include "server/uploads.hpp"

namespace server {

struct ServerOptions {
  std::string host = "127.0.0.1";  // loopback unless the operator says otherwise
  int port = 8080;                 // 0: any free port
  int ws_port = -1;                // -1: port + 1 (any free port when port is 0); 0: any free port
  /// A bundled character name, or a character file offered to the page under its file name.
  std::string character = "human48";
  std::string data_dir;  // empty: sessions are kept in memory only
  std::string web_root;  // empty: default_web_root()
  std::size_t max_live_sessions = RegistryOptions::kDefaultMaxLive;  // in memory at once
  int expire_days = 0;         // > 0: sessions untouched for that many days are deleted
  unsigned actor_threads = 0;  // threads running the sessions (0: one per core, at least 2)
  /// How long an HTTP request waits for its session's actor before answering 503.
  std::chrono::milliseconds call_timeout{10000};
  /// How long a connection may take to send a request header (HTTP) or upgrade (WebSocket).
  std::chrono::milliseconds header_timeout{5000};
  animator::Limits limits;  // every session's budgets (animator/limits.hpp)
  UploadCaps uploads;       // largest upload per file type
};

/// The page's folder: $PINDRAG_WEB_ROOT, else the source tree's web/ recorded at build time.
std::string default_web_root();
/// The addresses a server listening on `host` is reached at: `host` itself, or for a wildcard
/// (0.0.0.0: IPv4, ::: both families) the addresses of the machine's interfaces.
std::vector<std::string> listen_addresses(const std::string& host);

class Server {
 public:
  /// Loads the character, restores saved sessions and binds both ports.
  /// @throws std::runtime_error naming the address, the character or the folder that failed
  explicit Server(const ServerOptions& options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  void start();
  /// Idempotent; returns when both threads have ended.
  void stop();

  int http_port() const;
  int ws_port() const;
  /// The page's URL, with ?character=NAME when the character is not the page's default and
  /// ?key=K when creating sessions needs the server key.
  std::string url() const;
  /// The key that creating and listing sessions needs when the server listens beyond loopback
  /// ("" on loopback): kept in <data-dir>/server.key (0600), so bookmarks survive a restart.
  const std::string& server_key() const;
  /// How many saved sessions were restored at startup.
  int restored_sessions() const;
  SessionRegistry& registry();
  std::size_t ws_connections() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace server
