// A cpp-httplib server in which no connection holds a worker thread while it is still sending
// its request header. httplib gives each connection a pool thread from accept to close, so a few
// clients that send half a header and wait (slowloris) hold every thread and nothing else gets
// answered. Here an accepted connection first waits in the gate: one thread (epoll) collects
// its header bytes, and only a complete header goes to a worker thread, which runs httplib's
// own request processing on it. A header not complete within `header_timeout` (counted from
// the accept, or from the end of the previous request on a kept-alive connection) closes the
// connection; so does a header above kMaxHeaderBytes (after a 431).
//
// Threads: httplib's accept loop hands sockets over (it must use inline_task_queue()); the gate
// thread reads headers; `workers` threads process requests. The socket of a request belongs to
// exactly one of them at a time.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>

// httplib.h after Eigen (see http_routes.hpp)
#include <httplib.h>

namespace server {

struct GateLimits {
  std::chrono::milliseconds header_timeout{5000};
  int workers = 16;
  std::size_t max_waiting = 1024;  // connections in the gate at once; more are closed at once
};

class GatedHttpServer final : public httplib::Server {
 public:
  static constexpr std::size_t kMaxHeaderBytes = 16 * 1024;

  explicit GatedHttpServer(GateLimits limits = {});
  ~GatedHttpServer() override;
  GatedHttpServer(const GatedHttpServer&) = delete;
  GatedHttpServer& operator=(const GatedHttpServer&) = delete;

  /// After bind_to_port(): lets the kernel queue SOMAXCONN connections instead of httplib's 5,
  /// so a burst of connections waits for accept instead of having its SYNs dropped (a client
  /// retries those only after a second).
  void widen_listen_backlog();
  /// After listen_after_bind() returned: closes the connections in the gate and waits for the
  /// requests in progress. Idempotent.
  void shut_down();
  /// Connections waiting for a header now (for tests).
  std::size_t waiting() const;

 private:
  struct Impl;
  struct Connection;
  class Stream;

  // httplib's accept loop calls this (through its task queue) for every accepted socket
  bool process_and_close_socket(socket_t sock) override;
  void serve(Connection connection);

  std::unique_ptr<Impl> impl_;
};

}  // namespace server
