#include "server/server.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "io/bundled_characters.hpp"
#include "server/http_gate.hpp"
#include "server/http_routes.hpp"  // includes httplib.h after Eigen
#include "server/security.hpp"
#include "server/session_store.hpp"
#include "server/uploads.hpp"
#include "server/ws_endpoint.hpp"

namespace server {
namespace fs = std::filesystem;

std::string default_web_root() {
  if (const char* env = std::getenv("PINDRAG_WEB_ROOT"); env && *env) return env;
  return PINDRAG_DEFAULT_WEB_ROOT;
}

std::vector<std::string> listen_addresses(const std::string& host) {
  if (!is_wildcard_address(host)) return {host};
  const bool both = host != "0.0.0.0";  // an IPv6 wildcard takes IPv4 too (dual stack)
  std::vector<std::string> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return out;
  for (const ifaddrs* i = list; i; i = i->ifa_next) {
    if (!i->ifa_addr) continue;
    char text[INET6_ADDRSTRLEN] = {};
    const int family = i->ifa_addr->sa_family;
    if (family == AF_INET) {
      ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(i->ifa_addr)->sin_addr, text,
                  sizeof text);
    } else if (family == AF_INET6 && both) {
      ::inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(i->ifa_addr)->sin6_addr, text,
                  sizeof text);
    }
    if (*text && std::find(out.begin(), out.end(), text) == out.end()) out.emplace_back(text);
  }
  ::freeifaddrs(list);
  return out;
}

namespace {

// The key for creating sessions on a server reachable from other machines: the one kept in the
// data directory, else a new one (kept there when there is a data directory).
std::string load_or_make_server_key(const std::string& data_dir) {
  const fs::path path = data_dir.empty() ? fs::path() : fs::path(data_dir) / "server.key";
  if (!path.empty()) {
    std::ifstream in(path);
    std::string key;
    if (in >> key && is_valid_id(key)) return key;
  }
  const std::string key = random_hex(16);
  if (!path.empty()) {
    fs::create_directories(path.parent_path());
    write_private_file(path.string(), key);
  }
  return key;
}

}  // namespace

struct Server::Impl {
  explicit Impl(const ServerOptions& o)
      : options(o),
        registry(RegistryOptions{.data_dir = o.data_dir,
                                 .max_live = o.max_live_sessions,
                                 .expire_days = o.expire_days,
                                 .actor_threads = o.actor_threads,
                                 .limits = o.limits}),
        policy(o.host, 0, 0),
        http(GateLimits{.header_timeout = o.header_timeout}),
        ws(registry, policy, o.header_timeout) {}

  ServerOptions options;
  SessionRegistry registry;
  HostPolicy policy;
  RouteContext routes;
  GatedHttpServer http;
  WsEndpoint ws;
  std::thread http_thread;
  int http_port = 0;
  int ws_port = 0;
  int restored = 0;
  bool started = false;
  bool stopped = false;
};

Server::Server(const ServerOptions& options) : impl_(std::make_unique<Impl>(options)) {
  Impl& s = *impl_;
  s.routes.registry = &s.registry;
  s.routes.policy = &s.policy;
  s.routes.call_timeout = options.call_timeout;
  if (!is_loopback_host(options.host))
    s.routes.server_key = load_or_make_server_key(options.data_dir);
  if (const std::string e = animator::check_limits(options.limits); !e.empty())
    throw std::runtime_error(e);
  s.routes.uploads = UploadRules{options.uploads, options.limits};
  s.routes.web_root = options.web_root.empty() ? default_web_root() : options.web_root;
  if (!fs::is_regular_file(fs::path(s.routes.web_root) / "index.html")) {
    throw std::runtime_error("web root " + s.routes.web_root +
                             ": no index.html there (rule: --web-root names the page's folder)");
  }
  if (!options.data_dir.empty())
    s.routes.temp_root = (fs::path(options.data_dir) / "uploads").string();

  // the character: a bundled name, or a file the operator chose (checked now, loaded per session)
  bool bundled = false;
  for (const auto& c : io::bundled_characters()) bundled = bundled || c.name == options.character;
  if (!bundled) {
    if (!fs::is_regular_file(options.character)) {
      throw std::runtime_error("--character " + options.character +
                               ": neither a bundled character nor a file");
    }
    // throws naming the file when it does not load or its clip is over the budget
    session_from_file(options.character, "check", options.limits);
    s.routes.served_character_name =
        safe_file_name(fs::path(options.character).stem().string(), "character");
    s.routes.served_character_path = fs::absolute(options.character).string();
  }

  s.restored = s.registry.restore(std::cerr);

  // SO_REUSEADDR only (httplib's default adds SO_REUSEPORT, which lets a second server bind the
  // same port silently)
  s.http.set_socket_options([](socket_t sock) {
    int yes = 1;
    ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  const std::string bind_host = options.host == "localhost" ? "127.0.0.1" : options.host;
  if (options.port == 0) {
    s.http_port = s.http.bind_to_any_port(bind_host);
    if (s.http_port < 0) throw std::runtime_error("cannot listen on " + options.host + " (HTTP)");
  } else {
    if (!s.http.bind_to_port(bind_host, options.port)) {
      throw std::runtime_error("cannot listen on " + options.host + ":" +
                               std::to_string(options.port) +
                               " (HTTP; in use by another program?)");
    }
    s.http_port = options.port;
  }
  s.http.widen_listen_backlog();
  const int ws_request =
      options.ws_port >= 0 ? options.ws_port : (options.port == 0 ? 0 : options.port + 1);
  try {
    s.ws_port = s.ws.bind(bind_host, ws_request);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot listen on " + options.host + ":" + std::to_string(ws_request) +
                             " (WebSocket): " + e.what());
  }
  s.policy = HostPolicy(options.host, s.http_port, s.ws_port, listen_addresses(bind_host));
  register_routes(s.http, s.routes);
}

Server::~Server() { stop(); }

void Server::start() {
  Impl& s = *impl_;
  if (s.started) return;
  s.started = true;
  s.ws.start();
  s.http_thread = std::thread([&s] { s.http.listen_after_bind(); });
  // httplib's stop() does nothing before the server runs: wait for it, so stop() cannot be lost
  for (int k = 0; k < 2000 && !s.http.is_running(); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void Server::stop() {
  Impl& s = *impl_;
  if (s.stopped) return;
  s.stopped = true;
  s.http.stop();
  if (s.http_thread.joinable()) s.http_thread.join();
  s.http.shut_down();
  s.ws.stop();
  s.registry.stop_all();
}

int Server::http_port() const { return impl_->http_port; }
int Server::ws_port() const { return impl_->ws_port; }
int Server::restored_sessions() const { return impl_->restored; }
SessionRegistry& Server::registry() { return impl_->registry; }
std::size_t Server::ws_connections() const { return impl_->ws.connections(); }

const std::string& Server::server_key() const { return impl_->routes.server_key; }

std::string Server::url() const {
  std::string query;
  const std::string& name = impl_->routes.served_character_name;
  if (!name.empty()) {
    query = "character=" + name;
  } else if (impl_->options.character != "human48") {
    query = "character=" + impl_->options.character;
  }
  if (!server_key().empty())
    query += (query.empty() ? "" : "&") + std::string("key=") + server_key();
  return impl_->policy.page_origin() + "/" + (query.empty() ? "" : "?" + query);
}

}  // namespace server
