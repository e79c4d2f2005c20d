// Every HTTP route of docs/protocol.md on a cpp-httplib server: the page and its static files,
// three.js under /vendor/three/, the REST API, uploads, exports and thumbnails; the Host and
// Origin checks run before routing, and every refusal is a 4xx with a JSON {"error": ...} body.
// Handlers run on httplib's worker threads: they parse, call the session's actor and serialize;
// a session busy for longer than call_timeout gets 503 with Retry-After instead of a wait.
#pragma once

#include <chrono>
#include <string>

// before httplib.h: glibc's <resolv.h>, which it includes, defines a macro `_res` that breaks
// Eigen's headers when they come later
#include "server/security.hpp"
#include "server/session_registry.hpp"
#include "server/uploads.hpp"

#include <httplib.h>

namespace server {

struct RouteContext {
  SessionRegistry* registry = nullptr;
  /// How long a handler waits for a session's actor before answering 503 with Retry-After.
  std::chrono::milliseconds call_timeout{10000};
  /// Needed (header X-Server-Key) to create or list sessions; empty: not needed (loopback).
  std::string server_key;
  const HostPolicy* policy = nullptr;
  std::string web_root;   // the page: index.html, js/, css/ (node_modules/three for /vendor/three/)
  std::string temp_root;  // where uploads are unpacked (empty: the system's temporary folder)
  UploadRules uploads;    // caps by file type and the budgets of what uploads bring
  // a character file chosen by the operator (`serve --character FILE`), offered by this name
  // besides the bundled ones; empty: none
  std::string served_character_name;
  std::string served_character_path;
};

/// Registers all routes, the pre-routing checks, the error handler and the payload cap.
/// `context` (and what it points to) must outlive the server.
void register_routes(httplib::Server& http, const RouteContext& context);

}  // namespace server
