#include "server/server.hpp"

#include <sys/socket.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "io/bundled_characters.hpp"
#include "server/http_routes.hpp"  // includes httplib.h after Eigen
#include "server/security.hpp"
#include "server/uploads.hpp"
#include "server/ws_endpoint.hpp"

namespace server {
namespace fs = std::filesystem;

std::string default_web_root() {
  if (const char* env = std::getenv("PINDRAG_WEB_ROOT"); env && *env) return env;
  return PINDRAG_DEFAULT_WEB_ROOT;
}

struct Server::Impl {
  explicit Impl(const ServerOptions& o)
      : options(o), registry(o.data_dir, o.limits), policy(o.host, 0, 0), ws(registry, policy) {}

  ServerOptions options;
  SessionRegistry registry;
  HostPolicy policy;
  RouteContext routes;
  httplib::Server http;
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
  s.http.new_task_queue = [] { return new httplib::ThreadPool(8); };
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
  const int ws_request =
      options.ws_port >= 0 ? options.ws_port : (options.port == 0 ? 0 : options.port + 1);
  try {
    s.ws_port = s.ws.bind(bind_host, ws_request);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot listen on " + options.host + ":" + std::to_string(ws_request) +
                             " (WebSocket): " + e.what());
  }
  s.policy = HostPolicy(options.host, s.http_port, s.ws_port);
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
  s.ws.stop();
  s.registry.stop_all();
}

int Server::http_port() const { return impl_->http_port; }
int Server::ws_port() const { return impl_->ws_port; }
int Server::restored_sessions() const { return impl_->restored; }
SessionRegistry& Server::registry() { return impl_->registry; }
std::size_t Server::ws_connections() const { return impl_->ws.connections(); }

std::string Server::url() const {
  std::string url = impl_->policy.page_origin() + "/";
  const std::string& name = impl_->routes.served_character_name;
  if (!name.empty()) {
    url += "?character=" + name;
  } else if (impl_->options.character != "human48") {
    url += "?character=" + impl_->options.character;
  }
  return url;
}

}  // namespace server
