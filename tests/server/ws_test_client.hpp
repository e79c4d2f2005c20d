// Test clients of the server: a blocking Beast WebSocket client with a receive timeout (a test
// never hangs), and raw HTTP requests sent byte for byte (so no client library normalizes a
// hostile path before it reaches the server).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace server_test {

/// The decoded header and link 0..n-1 world positions of a PDPF pose frame.
struct PoseFrame {
  std::uint32_t magic = 0;
  std::uint16_t version = 0;
  std::uint16_t links = 0;
  std::uint32_t frame_id = 0;
  std::uint32_t last_seq = 0;
  double time = 0;
  std::vector<std::array<float, 11>> values;  // per link: p (3), world R (4), joint R (4)
};
/// @throws std::runtime_error when the size does not match the header
PoseFrame decode_pose(const std::string& bytes);

struct WsMessage {
  bool text = false;
  std::string data;
  nlohmann::json json() const { return nlohmann::json::parse(data); }
};

class WsClient {
 public:
  /// Connects and upgrades; `origin` empty: no Origin header.
  /// @throws std::runtime_error with the HTTP status of a refused upgrade ("status 403")
  WsClient(int port,
           const std::string& target,
           const std::string& origin,
           const std::string& host = "");
  ~WsClient();
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  void send(const nlohmann::json& message);
  void send_text(const std::string& text);
  void send_binary(const std::string& bytes);
  /// The next message. @throws std::runtime_error on timeout (the connection is then closed) or
  /// close
  WsMessage read(std::chrono::milliseconds timeout = std::chrono::seconds(10));
  /// Reads until a text message of this type arrives (skipping others).
  nlohmann::json read_until(const std::string& type);
  /// After the server closed: the close code it sent (0 when none).
  int close_code() const;
  void close();

 private:
  struct Impl;
  Impl* impl_;
};

struct HttpReply {
  int status = 0;
  std::string body;
};
/// Sends `request` verbatim to 127.0.0.1:port and reads the reply until the server closes.
HttpReply raw_http(int port, const std::string& request);

}  // namespace server_test
