#include "tests/server/ws_test_client.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstring>
#include <functional>
#include <stdexcept>

namespace server_test {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

constexpr auto kReadTimeout = std::chrono::seconds(10);

// Runs the asynchronous operations started on `ioc` until they finish or `timeout` passes; then
// the socket is closed (which ends them) and false is returned, so a test fails instead of hanging.
bool run_for(asio::io_context& ioc,
             tcp::socket& socket,
             std::chrono::steady_clock::duration timeout) {
  ioc.restart();
  ioc.run_for(timeout);
  if (ioc.stopped()) return true;
  beast::error_code ignored;
  socket.close(ignored);
  ioc.restart();
  ioc.run();
  return false;
}

}  // namespace

PoseFrame decode_pose(const std::string& b) {
  PoseFrame f;
  if (b.size() < 36) throw std::runtime_error("pose frame shorter than its header");
  std::memcpy(&f.magic, b.data(), 4);
  std::memcpy(&f.version, b.data() + 4, 2);
  std::memcpy(&f.links, b.data() + 6, 2);
  std::memcpy(&f.frame_id, b.data() + 8, 4);
  std::memcpy(&f.last_seq, b.data() + 12, 4);
  std::memcpy(&f.time, b.data() + 16, 8);
  if (b.size() != 36 + 44 * static_cast<size_t>(f.links))
    throw std::runtime_error("pose frame size mismatch");
  f.values.resize(f.links);
  for (size_t i = 0; i < f.links; ++i) std::memcpy(f.values[i].data(), b.data() + 36 + 44 * i, 44);
  return f;
}

struct WsClient::Impl {
  asio::io_context ioc;
  websocket::stream<tcp::socket> ws{ioc};
  beast::flat_buffer buffer;
};

WsClient::WsClient(int port,
                   const std::string& target,
                   const std::string& origin,
                   const std::string& host)
    : impl_(new Impl) {
  try {
    tcp::endpoint endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port));
    impl_->ws.next_layer().connect(endpoint);
    impl_->ws.next_layer().set_option(tcp::no_delay(true));  // as browsers do
    impl_->ws.read_message_max(std::size_t{64} << 20);
    impl_->ws.set_option(websocket::stream_base::decorator([origin](websocket::request_type& req) {
      if (!origin.empty()) req.set(http::field::origin, origin);
    }));
    // the asynchronous handshake keeps the response of a refused upgrade (the blocking one drops
    // it)
    websocket::response_type response;
    beast::error_code ec;
    impl_->ws.async_handshake(response, host.empty() ? "127.0.0.1:" + std::to_string(port) : host,
                              target, [&ec](beast::error_code result) { ec = result; });
    if (!run_for(impl_->ioc, impl_->ws.next_layer(), kReadTimeout))
      throw std::runtime_error("handshake: timed out");
    if (ec)
      throw std::runtime_error("status " + std::to_string(response.result_int()) + ": " +
                               ec.message());
  } catch (...) {
    delete impl_;
    throw;
  }
}

WsClient::~WsClient() {
  beast::error_code ec;
  impl_->ws.next_layer().close(ec);
  delete impl_;
}

void WsClient::send(const nlohmann::json& message) { send_text(message.dump()); }

void WsClient::send_text(const std::string& text) {
  impl_->ws.text(true);
  impl_->ws.write(asio::buffer(text));
}

void WsClient::send_binary(const std::string& bytes) {
  impl_->ws.binary(true);
  impl_->ws.write(asio::buffer(bytes));
}

WsMessage WsClient::read(std::chrono::milliseconds timeout) {
  impl_->buffer.clear();
  beast::error_code ec;
  impl_->ws.async_read(impl_->buffer,
                       [&ec](beast::error_code result, std::size_t) { ec = result; });
  if (!run_for(impl_->ioc, impl_->ws.next_layer(), timeout))
    throw std::runtime_error("read: timed out");
  if (ec) throw std::runtime_error("read: " + ec.message());
  return WsMessage{impl_->ws.got_text(), beast::buffers_to_string(impl_->buffer.data())};
}

nlohmann::json WsClient::read_until(const std::string& type) {
  for (int k = 0; k < 100000; ++k) {
    const WsMessage m = read();
    if (!m.text) continue;
    nlohmann::json j = m.json();
    if (j.value("type", "") == type) return j;
  }
  throw std::runtime_error("no " + type + " message");
}

int WsClient::close_code() const { return static_cast<int>(impl_->ws.reason().code); }

void WsClient::close() {
  beast::error_code ec;
  impl_->ws.close(websocket::close_code::normal, ec);
}

HttpReply raw_http(int port, const std::string& request) {
  asio::io_context ioc;
  tcp::socket socket(ioc);
  socket.connect(
      tcp::endpoint(asio::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port)));
  asio::write(socket, asio::buffer(request));
  // read until the server closes or one whole response (by Content-Length) has arrived
  std::string reply;
  char chunk[4096];
  std::function<void()> read_more = [&] {
    socket.async_read_some(asio::buffer(chunk), [&](beast::error_code ec, std::size_t n) {
      reply.append(chunk, n);
      if (ec) return;
      const size_t header_end = reply.find("\r\n\r\n");
      const size_t length_at = reply.find("Content-Length: ");
      if (header_end != std::string::npos && length_at != std::string::npos &&
          length_at < header_end) {
        const size_t length = std::stoul(reply.substr(length_at + 16));
        if (reply.size() >= header_end + 4 + length) return;
      }
      read_more();
    });
  };
  read_more();
  if (!run_for(ioc, socket, kReadTimeout)) throw std::runtime_error("HTTP reply: timed out");
  HttpReply out;
  if (reply.rfind("HTTP/1.", 0) == 0 && reply.size() > 12)
    out.status = std::stoi(reply.substr(9, 3));
  const size_t header_end = reply.find("\r\n\r\n");
  if (header_end != std::string::npos) out.body = reply.substr(header_end + 4);
  return out;
}

}  // namespace server_test
