// Security checks of a local web tool (reference/ecosystem.md §7.1): which Host headers and
// Origins the server answers (DNS rebinding, cross-site WebSockets and form posts), constant-time
// token comparison, random ids, and resolving a URL path to a file without leaving a root.
// Pure functions over strings and the file system; no sockets, no HTTP library.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace server {

/// The Host headers and Origins of this server: the loopback names (127.0.0.1, localhost,
/// [::1]), the listen host (when it names one address) and, for a wildcard listen host (0.0.0.0,
/// ::), the addresses the server is reachable at (`local_addresses`, e.g. from
/// interface_addresses()), each with the HTTP or WebSocket port. No other name or IP literal.
class HostPolicy {
 public:
  HostPolicy(std::string listen_host,
             int http_port,
             int ws_port,
             const std::vector<std::string>& local_addresses = {});

  /// `Host` header of a request to `port` (the HTTP or the WebSocket port): "127.0.0.1:8080",
  /// "localhost.:8080" (trailing dot allowed), "[::1]:8080"; names compare without case.
  bool host_allowed(std::string_view host_header, int port) const;
  /// The header names one of our pages exactly: "http://<allowed host>:<http_port>".
  bool origin_allowed(std::string_view origin) const;
  /// The host part of a Host header (without port or trailing dot), for building URLs; empty
  /// when malformed.
  static std::string host_name(std::string_view host_header);
  /// "http://127.0.0.1:8080" for the listen host (a wildcard becomes 127.0.0.1).
  std::string page_origin() const;

  int http_port() const { return http_port_; }
  int ws_port() const { return ws_port_; }

 private:
  bool name_allowed(std::string_view name) const;
  std::string listen_host_;
  int http_port_;
  int ws_port_;
  bool wildcard_;
  std::vector<std::string> local_names_;  // as they appear in a Host header ("[v6]")
};

/// True for 127.0.0.0/8, ::1 and IPv4-mapped loopback (::ffff:127.x.y.z).
bool is_loopback_address(std::string_view address);
/// True for 0.0.0.0 and :: (listen on every interface).
bool is_wildcard_address(std::string_view address);
/// True when the host listens on loopback only (127.0.0.1, ::1, localhost).
bool is_loopback_host(std::string_view host);

/// Compares in time independent of where the strings differ (only their lengths leak).
bool tokens_equal(std::string_view a, std::string_view b);

/// `bytes` random bytes as lowercase hex, from /dev/urandom (std::random_device if unreadable).
std::string random_hex(size_t bytes);
/// A session id or token as random_hex makes them: 32 lowercase hex digits (128 bits).
bool is_valid_id(std::string_view id);

/// Resolves a percent-decoded URL path (relative to `root`, leading '/' ignored) to a regular
/// file inside `root`. Refused, with `why` set: NUL or backslash, an empty, "." or ".." segment,
/// a hidden segment (".git"), a segment in `forbidden_segments` ("node_modules"), a path that
/// is absolute after the leading '/', and anything whose canonical path (symlinks resolved)
/// lies outside the canonical root or is not a regular file.
std::optional<std::filesystem::path> resolve_static_path(
    const std::filesystem::path& root,
    std::string_view url_path,
    const std::vector<std::string>& forbidden_segments,
    std::string* why = nullptr);

/// `s` with its ASCII letters in lower case (host names, header names, file extensions).
std::string lower(std::string_view s);

/// A name safe as a file name and in Content-Disposition: [A-Za-z0-9._-]{1,64}, other bytes
/// become '_', no leading dot; `fallback` when nothing remains.
std::string safe_file_name(std::string_view name, std::string_view fallback);

}  // namespace server
