// The WebSocket side of docs/protocol.md (Boost.Beast): /ws?session=ID&token=T on its own port.
// The upgrade is refused (403/401/404, a JSON body) unless the Host names this server, the
// Origin, when sent, is this server's page exactly, and the token is the session's. Messages
// are capped at 1 MiB (close 1009). Each connection keeps its JSON messages in order (at most
// kMaxQueuedTextBytes unsent, else it is dropped) and one pending pose frame that a newer frame
// overwrites, so a client that reads slowly gets the newest pose and never a backlog.
//
// The upgrade request and the handshake must complete within the handshake timeout; an open
// connection from which nothing (not even a pong) arrives for kIdleTimeout is closed. When
// accept fails (no descriptors left), the endpoint says so once and waits kAcceptBackoff before
// trying again instead of spinning.
//
// Threads: one I/O thread runs every connection; session actors hand messages to a connection
// from their own threads through a small locked outbox. Beast stays inside ws_endpoint.cpp.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "server/security.hpp"
#include "server/session_registry.hpp"

namespace server {

class Connection;

class WsEndpoint {
 public:
  /// Unsent JSON bytes a connection may hold before it is closed as too slow.
  static constexpr std::size_t kMaxQueuedTextBytes = std::size_t{4} << 20;

  /// Wait after an accept failed (out of descriptors) before accepting again.
  static constexpr std::chrono::milliseconds kAcceptBackoff{250};
  /// A connection that sent nothing for this long is closed (a ping goes out at half of it).
  static constexpr std::chrono::seconds kIdleTimeout{60};

  /// `policy` is read on every upgrade; it may be reassigned before start() (ports known after
  /// binding) and must outlive the endpoint. `handshake_timeout` bounds the upgrade request and
  /// the WebSocket handshake.
  WsEndpoint(SessionRegistry& registry,
             const HostPolicy& policy,
             std::chrono::milliseconds handshake_timeout = std::chrono::seconds(5));
  ~WsEndpoint();
  WsEndpoint(const WsEndpoint&) = delete;
  WsEndpoint& operator=(const WsEndpoint&) = delete;

  /// Binds and listens (port 0: any free port). Returns the port.
  /// @throws std::system_error naming the address when it cannot bind
  int bind(const std::string& host, int port);
  /// Starts the I/O thread.
  void start();
  /// Closes the acceptor, stops the I/O thread and joins it. Idempotent.
  void stop();
  /// Connections open now (for tests and the benchmark).
  std::size_t connections() const;

 private:
  friend class Connection;  // a client's connection (ws_endpoint.cpp) reaches the endpoint's state
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace server
