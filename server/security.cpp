#include "server/security.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <random>

namespace server {
std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

namespace {

bool is_ip_literal(std::string_view name) {
  if (name.size() >= 2 && name.front() == '[' && name.back() == ']') return true;  // IPv6
  if (name.empty()) return false;
  int dots = 0;
  for (char c : name) {
    if (c == '.') {
      ++dots;
    } else if (!std::isdigit(static_cast<unsigned char>(c))) {
      return false;
    }
  }
  return dots == 3;
}

// Splits "name:port" (name may be "[v6]"); false when the port is missing or not a number.
bool split_host_port(std::string_view header, std::string& name, int& port) {
  const size_t colon = header.rfind(':');
  if (colon == std::string_view::npos || colon == 0 || colon + 1 >= header.size()) return false;
  if (header.front() == '[' && header[colon - 1] != ']') return false;
  const std::string_view digits = header.substr(colon + 1);
  if (digits.size() > 5) return false;
  int value = 0;
  for (char c : digits) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
    value = value * 10 + (c - '0');
  }
  name = lower(header.substr(0, colon));
  if (!name.empty() && name.back() == '.') name.pop_back();
  port = value;
  return !name.empty();
}

// A bare IPv6 address as it appears in a Host header: "[fe80::1]".
std::string host_form(std::string_view address) {
  std::string a = lower(address);
  if (a.find(':') != std::string::npos && a.front() != '[') a = "[" + a + "]";
  return a;
}

}  // namespace

HostPolicy::HostPolicy(std::string listen_host,
                       int http_port,
                       int ws_port,
                       const std::vector<std::string>& local_addresses)
    : listen_host_(host_form(listen_host)),
      http_port_(http_port),
      ws_port_(ws_port),
      wildcard_(is_wildcard_address(listen_host)) {
  if (wildcard_) {
    for (const std::string& a : local_addresses) local_names_.push_back(host_form(a));
  }
}

bool HostPolicy::name_allowed(std::string_view name) const {
  if (name == "127.0.0.1" || name == "localhost" || name == "[::1]") return true;
  if (!wildcard_) return name == listen_host_;
  return std::find(local_names_.begin(), local_names_.end(), name) != local_names_.end();
}

bool HostPolicy::host_allowed(std::string_view host_header, int port) const {
  std::string name;
  int header_port = 0;
  if (!split_host_port(host_header, name, header_port)) return false;
  return header_port == port && name_allowed(name);
}

bool HostPolicy::origin_allowed(std::string_view origin) const {
  constexpr std::string_view kScheme = "http://";
  if (origin.substr(0, kScheme.size()) != kScheme) return false;
  const std::string_view rest = origin.substr(kScheme.size());
  if (rest.find('/') != std::string_view::npos) return false;  // an origin has no path
  std::string name;
  int port = 0;
  if (!split_host_port(rest, name, port)) return false;
  // an Origin never carries a trailing dot or upper case from a browser; compare what was sent
  if (lower(rest.substr(0, rest.rfind(':'))) != rest.substr(0, rest.rfind(':'))) return false;
  return port == http_port_ && name_allowed(name);
}

std::string HostPolicy::host_name(std::string_view host_header) {
  std::string name;
  int port = 0;
  if (!split_host_port(host_header, name, port)) return {};
  return name;
}

std::string HostPolicy::page_origin() const {
  const std::string host = wildcard_ ? "127.0.0.1" : listen_host_;
  return "http://" + host + ":" + std::to_string(http_port_);
}

bool is_loopback_address(std::string_view address) {
  std::string a = lower(address);
  if (a.size() >= 2 && a.front() == '[' && a.back() == ']') a = a.substr(1, a.size() - 2);
  if (a == "::1") return true;
  constexpr std::string_view kMapped = "::ffff:";
  if (a.rfind(kMapped, 0) == 0) a = a.substr(kMapped.size());
  return a.rfind("127.", 0) == 0 && is_ip_literal(a);
}

bool is_wildcard_address(std::string_view address) {
  return address == "0.0.0.0" || address == "::" || address == "[::]";
}

bool is_loopback_host(std::string_view host) {
  return lower(host) == "localhost" || is_loopback_address(host);
}

bool tokens_equal(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

std::string random_hex(size_t bytes) {
  std::string raw(bytes, '\0');
  std::ifstream urandom("/dev/urandom", std::ios::binary);
  if (!urandom.read(raw.data(), static_cast<std::streamsize>(bytes))) {
    std::random_device device;
    for (char& c : raw) c = static_cast<char>(device() & 0xFF);
  }
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  out.reserve(bytes * 2);
  for (char c : raw) {
    const auto u = static_cast<unsigned char>(c);
    out += kDigits[u >> 4];
    out += kDigits[u & 0xF];
  }
  return out;
}

bool is_valid_id(std::string_view id) {
  return id.size() == 32 && std::all_of(id.begin(), id.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

std::optional<std::filesystem::path> resolve_static_path(
    const std::filesystem::path& root,
    std::string_view url_path,
    const std::vector<std::string>& forbidden_segments,
    std::string* why) {
  namespace fs = std::filesystem;
  auto refuse = [&](const std::string& reason) -> std::optional<fs::path> {
    if (why) *why = reason;
    return std::nullopt;
  };
  if (url_path.find('\0') != std::string_view::npos) return refuse("the path holds a NUL byte");
  if (url_path.find('\\') != std::string_view::npos) return refuse("the path holds a backslash");
  std::string_view rest = url_path;
  if (!rest.empty() && rest.front() == '/') rest.remove_prefix(1);
  if (rest.empty()) return refuse("the path is empty");
  if (rest.front() == '/') return refuse("the path is absolute");
  fs::path relative;
  size_t start = 0;
  while (start <= rest.size()) {
    const size_t slash = std::min(rest.find('/', start), rest.size());
    const std::string_view segment = rest.substr(start, slash - start);
    if (segment.empty() || segment == "." || segment == "..") {
      return refuse("the path has an empty, '.' or '..' segment");
    }
    if (segment.front() == '.') return refuse("the path names a hidden file");
    for (const std::string& forbidden : forbidden_segments) {
      if (segment == forbidden) return refuse("the path enters " + forbidden);
    }
    relative /= std::string(segment);
    start = slash + 1;
  }
  std::error_code ec;
  const fs::path canonical_root = fs::canonical(root, ec);
  if (ec) return refuse("the static root does not exist");
  const fs::path candidate = fs::canonical(canonical_root / relative, ec);
  if (ec) return refuse("no such file");
  const auto [root_end, unused] = std::mismatch(canonical_root.begin(), canonical_root.end(),
                                                candidate.begin(), candidate.end());
  (void)unused;
  if (root_end != canonical_root.end()) return refuse("the path leaves the static root");
  if (!fs::is_regular_file(candidate, ec)) return refuse("not a regular file");
  return candidate;
}

std::string safe_file_name(std::string_view name, std::string_view fallback) {
  std::string out;
  for (char c : name.substr(0, 64)) {
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
    out += ok ? c : '_';
  }
  while (!out.empty() && out.front() == '.') out.erase(out.begin());
  if (out.empty() || out.find_first_not_of('_') == std::string::npos) return std::string(fallback);
  return out;
}

}  // namespace server
