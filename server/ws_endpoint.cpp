#include "server/ws_endpoint.hpp"

#include <atomic>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <thread>

#include "server/protocol.hpp"

namespace server {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {

std::atomic<std::uint64_t> next_connection_id{1};

// "session=...&token=..." of "/ws?session=...&token=..."; empty strings when absent.
bool parse_target(std::string_view target, std::string& session, std::string& token) {
  const size_t question = target.find('?');
  if (target.substr(0, question) != "/ws") return false;
  if (question == std::string_view::npos) return true;
  std::string_view query = target.substr(question + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const size_t eq = pair.find('=');
    if (eq != std::string_view::npos) {
      const std::string_view key = pair.substr(0, eq);
      const std::string_view value = pair.substr(eq + 1);
      if (key == "session") session = std::string(value);
      if (key == "token") token = std::string(value);
    }
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return true;
}

}  // namespace

class Connection;

struct WsEndpoint::Impl {
  Impl(SessionRegistry& r, const HostPolicy& p, std::chrono::milliseconds handshake)
      : registry(r), policy(p), handshake_timeout(handshake), acceptor(ioc), backoff(ioc) {}
  void accept();
  void on_accept_failed(const beast::error_code& ec);

  SessionRegistry& registry;
  const HostPolicy& policy;
  const std::chrono::milliseconds handshake_timeout;
  bool accept_failing = false;  // I/O thread only: a failure was reported and not yet recovered
  // declared before the io_context: connections still queued in it count down when it goes
  std::atomic<std::size_t> open_connections{0};
  bool stopped = false;
  asio::io_context ioc;
  tcp::acceptor acceptor;
  asio::steady_timer backoff;
  std::thread thread;
};

/// One WebSocket client. Lives on the I/O thread; actors reach it through its Outbox.
class Connection : public std::enable_shared_from_this<Connection> {
 public:
  Connection(tcp::socket socket, WsEndpoint::Impl& endpoint)
      : ws_(std::move(socket)), endpoint_(endpoint), id_(next_connection_id++) {
    ++endpoint_.open_connections;
  }
  ~Connection() {
    if (actor_) actor_->unsubscribe(id_);
    --endpoint_.open_connections;
  }

  void start() {
    beast::get_lowest_layer(ws_).expires_after(endpoint_.handshake_timeout);
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(4 * 1024);
    http::async_read(ws_.next_layer(), buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) {
                       self->on_upgrade_request(ec);
                     });
  }

  // --- called from actor threads -------------------------------------------------------------
  void queue_text(std::string text) {
    {
      std::lock_guard lock(out_mutex_);
      if (dropped_) return;
      queued_text_bytes_ += text.size();
      if (queued_text_bytes_ > WsEndpoint::kMaxQueuedTextBytes) {
        dropped_ = true;  // the client does not read: close it rather than buffer without bound
      } else {
        texts_.push_back(std::move(text));
      }
    }
    schedule_flush();
  }
  void queue_pose(std::string frame) {
    {
      std::lock_guard lock(out_mutex_);
      if (dropped_) return;
      pose_ = std::move(frame);  // latest wins: an unsent older frame is overwritten
    }
    schedule_flush();
  }

 private:
  class Subscriber final : public SessionSubscriber {
   public:
    explicit Subscriber(std::weak_ptr<Connection> c) : connection_(std::move(c)) {}
    void send_text(std::string message) override {
      if (auto c = connection_.lock()) c->queue_text(std::move(message));
    }
    void send_pose(std::string frame) override {
      if (auto c = connection_.lock()) c->queue_pose(std::move(frame));
    }

   private:
    std::weak_ptr<Connection> connection_;
  };

  void schedule_flush() {
    if (flush_scheduled_.exchange(true)) return;
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
      self->flush_scheduled_ = false;
      self->write_next();
    });
  }

  void refuse(http::status status, const std::string& message) {
    auto res = std::make_shared<http::response<http::string_body>>(status, 11);
    res->set(http::field::content_type, "application/json");
    res->set(http::field::connection, "close");
    res->body() = nlohmann::json{{"error", message}}.dump(-1, ' ', false,
                                                          nlohmann::json::error_handler_t::replace);
    res->prepare_payload();
    http::async_write(
        ws_.next_layer(), *res, [self = shared_from_this(), res](beast::error_code, std::size_t) {
          beast::error_code ignored;
          beast::get_lowest_layer(self->ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
        });
  }

  void on_upgrade_request(beast::error_code ec) {
    if (ec) return;  // timed out, too large or not HTTP: drop the socket
    const auto& req = parser_->get();
    const std::string host(req[http::field::host]);
    if (!endpoint_.policy.host_allowed(host, endpoint_.policy.ws_port())) {
      return refuse(http::status::forbidden, "Host: not a name of this server");
    }
    if (!websocket::is_upgrade(req)) {
      return refuse(http::status::bad_request,
                    "Upgrade: this port speaks WebSocket only (/ws?session=ID&token=T)");
    }
    const auto origin = req.find(http::field::origin);
    if (origin != req.end() && !endpoint_.policy.origin_allowed(std::string(origin->value()))) {
      return refuse(http::status::forbidden, "Origin: not this server's page (rule: exactly " +
                                                 endpoint_.policy.page_origin() + ")");
    }
    std::string session, token;
    if (!parse_target(std::string(req.target()), session, token)) {
      return refuse(http::status::not_found, "path: the WebSocket is at /ws");
    }
    if (!is_valid_id(session)) return refuse(http::status::not_found, "session: no such session");
    SessionLookup found;
    try {
      found = endpoint_.registry.find(session, token);
    } catch (const std::exception& e) {
      // every live session is in use, or the saved session does not load
      return refuse(http::status::service_unavailable, std::string("session: ") + e.what());
    }
    if (found.status == 404) return refuse(http::status::not_found, "session: no such session");
    if (found.status != 200)
      return refuse(http::status::unauthorized, "token: missing or wrong session token");
    actor_ = found.actor;

    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout timeouts{};
    timeouts.handshake_timeout = endpoint_.handshake_timeout;
    timeouts.idle_timeout = WsEndpoint::kIdleTimeout;
    timeouts.keep_alive_pings = true;
    ws_.set_option(timeouts);
    ws_.read_message_max(kMaxWsMessageBytes);
    ws_.auto_fragment(false);
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code accept_ec) {
      if (accept_ec) return;
      self->accepted_ = true;
      self->read_next();
      self->write_next();
    });
  }

  void read_next() {
    in_.clear();
    ws_.async_read(
        in_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) return;  // closed, or too big (Beast has sent close 1009), or the socket failed
    if (!ws_.got_text()) {
      queue_text(error_message(
          nullptr, "message: binary frames are not accepted from clients (rule: JSON text)"));
      return read_next();
    }
    const std::string text = beast::buffers_to_string(in_.data());
    ClientRequest request;
    try {
      request = parse_client_message(text);
    } catch (const ProtocolError& e) {
      queue_text(error_message(e.id, e.what()));
      return read_next();
    }
    if (const auto* hello = std::get_if<Hello>(&request.message)) {
      if (hello->protocol != kProtocolVersion) {
        ws_.async_close(websocket::close_reason(websocket::close_code::protocol_error,
                                                "unsupported protocol version"),
                        [self = shared_from_this()](beast::error_code) {});
        return read_next();
      }
      if (!subscribed_) {
        subscribed_ = true;
        actor_->subscribe(id_, std::make_shared<Subscriber>(weak_from_this()));
      } else {
        queue_text(error_message(request.id, "hello: sent twice on one connection"));
      }
      return read_next();
    }
    if (!subscribed_) {
      queue_text(error_message(request.id,
                               "message: send hello first (rule: the first message is hello)"));
      return read_next();
    }
    actor_->post(id_, std::move(request));
    read_next();
  }

  void write_next() {
    if (writing_ || !accepted_) return;
    {
      std::lock_guard lock(out_mutex_);
      if (dropped_) {
        beast::error_code ignored;
        beast::get_lowest_layer(ws_).socket().close(ignored);
        return;
      }
      if (!texts_.empty()) {
        out_ = std::move(texts_.front());
        texts_.pop_front();
        queued_text_bytes_ -= out_.size();
        out_is_text_ = true;
      } else if (pose_) {
        out_ = std::move(*pose_);
        pose_.reset();
        out_is_text_ = false;
      } else {
        return;
      }
    }
    writing_ = true;
    ws_.text(out_is_text_);
    ws_.async_write(asio::buffer(out_),
                    [self = shared_from_this()](beast::error_code ec, std::size_t) {
                      self->writing_ = false;
                      if (ec) return;
                      self->write_next();
                    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  WsEndpoint::Impl& endpoint_;
  const std::uint64_t id_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  beast::flat_buffer in_;
  std::shared_ptr<SessionActor> actor_;
  bool accepted_ = false;
  bool subscribed_ = false;

  // outgoing: filled by actor threads, drained on the I/O thread
  std::mutex out_mutex_;
  std::deque<std::string> texts_;
  std::size_t queued_text_bytes_ = 0;
  std::optional<std::string> pose_;
  bool dropped_ = false;
  std::atomic<bool> flush_scheduled_{false};
  // I/O thread only
  std::string out_;
  bool out_is_text_ = true;
  bool writing_ = false;
};

void WsEndpoint::Impl::on_accept_failed(const beast::error_code& ec) {
  // out of descriptors (EMFILE, ENFILE) or another transient failure: the pending connection
  // stays in the backlog, so accepting again at once would fail again at once
  if (!accept_failing) {
    std::cerr << "pindrag serve: WebSocket accept failed (" << ec.message() << "); retrying every "
              << kAcceptBackoff.count() << " ms until it succeeds\n";
    accept_failing = true;
  }
  backoff.expires_after(kAcceptBackoff);
  backoff.async_wait([this](beast::error_code wait_ec) {
    if (!wait_ec && acceptor.is_open()) accept();
  });
}

void WsEndpoint::Impl::accept() {
  acceptor.async_accept(asio::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
    if (ec) {
      if (ec == asio::error::operation_aborted || !acceptor.is_open()) return;
      return on_accept_failed(ec);
    }
    if (accept_failing) std::cerr << "pindrag serve: WebSocket accepting again\n";
    accept_failing = false;
    // small frames go out at once (no Nagle delay), and the kernel holds little unsent data, so
    // the pending-pose slot, not a socket buffer, absorbs a slow reader
    beast::error_code ignored;
    socket.set_option(tcp::no_delay(true), ignored);
    socket.set_option(asio::socket_base::send_buffer_size(64 * 1024), ignored);
    std::make_shared<Connection>(std::move(socket), *this)->start();
    accept();
  });
}

WsEndpoint::WsEndpoint(SessionRegistry& registry,
                       const HostPolicy& policy,
                       std::chrono::milliseconds handshake_timeout)
    : impl_(std::make_unique<Impl>(registry, policy, handshake_timeout)) {}

WsEndpoint::~WsEndpoint() { stop(); }

int WsEndpoint::bind(const std::string& host, int port) {
  const tcp::endpoint endpoint(asio::ip::make_address(host == "localhost" ? "127.0.0.1" : host),
                               static_cast<unsigned short>(port));
  auto& acceptor = impl_->acceptor;
  acceptor.open(endpoint.protocol());
  acceptor.set_option(asio::socket_base::reuse_address(true));
  acceptor.bind(endpoint);
  acceptor.listen(asio::socket_base::max_listen_connections);
  return acceptor.local_endpoint().port();
}

void WsEndpoint::start() {
  impl_->accept();
  impl_->thread = std::thread([this] { impl_->ioc.run(); });
}

void WsEndpoint::stop() {
  if (impl_->stopped) return;
  impl_->stopped = true;
  asio::post(impl_->ioc, [this] {
    beast::error_code ignored;
    impl_->acceptor.close(ignored);
    impl_->backoff.cancel();
  });
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::size_t WsEndpoint::connections() const { return impl_->open_connections; }

}  // namespace server
