// Integration tests of a server that keeps answering: a busy session answers 503 with
// Retry-After while /api/health answers, connections that send half a header (slowloris) hold
// no thread and are closed after the header timeout (HTTP and WebSocket), a drag ends when its
// client disconnects, and a wildcard bind admits only the names it is reachable at.
#include "tests/server/server_fixture.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <atomic>
#include <chrono>

namespace {

using server_test::json;
using server_test::ServerTest;
using server_test::WsClient;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A TCP connection to 127.0.0.1:port that has sent `bytes` and then waits.
int open_and_send(int port, const std::string& bytes) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  if (::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(bytes.size())) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// True when the server closes `fd` (reads reach end of file) within `timeout`.
bool closed_by_server_within(int fd, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  char chunk[512];
  while (Clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    const int left = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
    if (::poll(&p, 1, std::max(left, 1)) <= 0) continue;
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) return true;
  }
  return false;
}

class ResilienceTest : public ServerTest {
 protected:
  void configure(server::ServerOptions& o) override {
    o.call_timeout = std::chrono::milliseconds(300);
    o.header_timeout = std::chrono::milliseconds(1000);
  }
  // GET /api/health; returns the seconds it took (a failed request counts as an hour)
  double health_seconds() {
    const auto t0 = Clock::now();
    auto c = http();
    const auto res = c.Get("/api/health");
    if (!res || res->status != 200) return 3600;
    return seconds_since(t0);
  }
};

TEST_F(ResilienceTest, ABusySessionAnswers503WithRetryAfterWhileHealthAnswers) {
  const Created s = create_session();
  const auto actor = actor_of(s);
  // the session is busy for two seconds with work that came first
  std::atomic<bool> started{false};
  std::thread busy([&] {
    actor->call([&](animator::Session&) {
      started = true;
      std::this_thread::sleep_for(std::chrono::seconds(2));
    });
  });
  while (!started) std::this_thread::sleep_for(std::chrono::milliseconds(1));

  // twenty requests for it at once: each gives up after the call timeout
  std::vector<std::thread> clients;
  std::vector<int> statuses(20, 0);
  std::vector<std::string> retry_after(20);
  std::vector<double> took(20, 0);
  for (int i = 0; i < 20; ++i) {
    clients.emplace_back([&, i] {
      const auto t0 = Clock::now();
      auto c = http();
      const auto res = c.Get("/api/sessions/" + s.id, {{"X-Session-Token", s.token}});
      took[i] = seconds_since(t0);
      if (!res) return;
      statuses[i] = res->status;
      retry_after[i] = res->get_header_value("Retry-After");
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const double health = health_seconds();
  for (auto& t : clients) t.join();
  busy.join();

  EXPECT_LT(health, 0.5) << "/api/health waited behind the busy session";
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(statuses[i], 503) << i;
    EXPECT_FALSE(retry_after[i].empty()) << i;
    EXPECT_LT(took[i], 1.5) << i;
  }
  std::cout << "busy session: /api/health in " << health * 1e3 << " ms, 503 after "
            << *std::max_element(took.begin(), took.end()) * 1e3 << " ms at most\n";
  // the session itself is fine afterwards
  EXPECT_EQ(snapshot(s).at("character").at("name"), "human48");
}

TEST_F(ResilienceTest, SlowHeadersDoNotDelayHealthAndAreClosedAfterTheTimeout) {
  const int port = server_->http_port();
  const std::string partial =
      "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nX-a: ";
  std::vector<int> slow;
  for (int i = 0; i < 40; ++i) {
    const int fd = open_and_send(port, partial);
    ASSERT_GE(fd, 0);
    slow.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  double worst = 0;
  for (int k = 0; k < 5; ++k) worst = std::max(worst, health_seconds());
  EXPECT_LT(worst, 1.0) << "40 connections with half a header delayed /api/health";
  std::cout << "40 slow headers held: /api/health in " << worst * 1e3 << " ms at most\n";
  // the header timeout (1 s here) closes them
  for (const int fd : slow) {
    EXPECT_TRUE(closed_by_server_within(fd, std::chrono::milliseconds(3000)));
    ::close(fd);
  }
  EXPECT_LT(health_seconds(), 1.0);
}

TEST_F(ResilienceTest, KeptAliveConnectionsServeSeveralRequests) {
  auto c = http();
  c.set_keep_alive(true);
  for (int i = 0; i < 4; ++i) {
    const auto res = c.Get("/api/health");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200);
  }
  const Created s = create_session();
  EXPECT_EQ(snapshot(s).at("session"), s.id);
}

TEST_F(ResilienceTest, ASlowWebSocketUpgradeIsClosedAfterTheTimeout) {
  const int port = server_->ws_port();
  const int fd = open_and_send(
      port, "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) + "\r\nUpgrade: webs");
  ASSERT_GE(fd, 0);
  // others connect meanwhile
  const Created s = create_session();
  EXPECT_EQ(connect(s)->read_until("snapshot").at("session"), s.id);
  const auto t0 = Clock::now();
  EXPECT_TRUE(closed_by_server_within(fd, std::chrono::milliseconds(3000)));
  std::cout << "slow upgrade closed after " << seconds_since(t0) * 1e3 << " ms more\n";
  ::close(fd);
}

TEST_F(ResilienceTest, ADragEndsWhenItsClientDisconnects) {
  const Created s = create_session();
  auto ws = connect(s);
  const json snap = ws->read_until("snapshot");
  std::array<double, 3> hand{};
  for (const json& l : snap.at("links")) {
    if (l.at("name") == "r_hand") {
      for (int k = 0; k < 3; ++k) hand[k] = l.at("p")[k];
    }
  }
  request(*ws, {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", hand}}, 1);
  for (std::uint32_t seq = 1; seq <= 5; ++seq) {
    ws->send({{"type", "drag_move"},
              {"seq", seq},
              {"target", {hand[0], hand[1] + 0.02 * seq, hand[2]}}});
  }
  request(*ws, {{"type", "pin"}, {"link", "l_foot"}}, 2);  // the moves above have been applied
  const auto actor = actor_of(s);
  ASSERT_TRUE(actor->call([](animator::Session& x) { return x.dragging(); }));
  ws.reset();  // the client goes away mid-drag (the socket closes without a drag_end)

  bool dragging = true;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (dragging && Clock::now() < deadline) {
    dragging = actor->call([](animator::Session& x) { return x.dragging(); });
    if (dragging) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_FALSE(dragging) << "the drag of a disconnected client is still active";
  // the gesture is one committed undo entry, saved like any other edit
  const json after = snapshot(s);
  EXPECT_TRUE(after.at("undo").at("can_undo").get<bool>());
  const json labels = after.at("undo").at("labels");
  ASSERT_FALSE(labels.empty());
  EXPECT_NE(labels.back().get<std::string>().find("drag"), std::string::npos) << labels.dump();
}

// A server listening on every interface.
class WildcardTest : public ServerTest {
 protected:
  void configure(server::ServerOptions& o) override { o.host = "0.0.0.0"; }
  std::string port_suffix() const { return ":" + std::to_string(server_->http_port()); }
  httplib::Headers with_key(httplib::Headers h) const {
    h.emplace("X-Server-Key", server_->server_key());
    return h;
  }
};

TEST_F(WildcardTest, ForeignIpLiteralsInHostAndOriginAreRefused) {
  ASSERT_FALSE(server_->server_key().empty());
  auto c = http();
  for (const std::string foreign : {"203.0.113.7", "10.255.255.254", "[2001:db8::7]"}) {
    const auto res = c.Get("/api/health", {{"Host", foreign + port_suffix()}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 403) << foreign;
    const auto post =
        c.Post("/api/sessions", with_key({{"Origin", "http://" + foreign + port_suffix()}}),
               json{{"character", "human48"}}.dump(), "application/json");
    EXPECT_EQ(post->status, 403) << foreign;
  }
  EXPECT_EQ(c.Get("/api/health", {{"Host", "127.0.0.1" + port_suffix()}})->status, 200);
  // the addresses it listens on are its names
  for (const std::string& address : server::listen_addresses("0.0.0.0")) {
    const auto res = c.Get("/api/health", {{"Host", address + port_suffix()}});
    EXPECT_EQ(res->status, 200) << address;
  }
  const Created s = create_session("human48", with_key({}));
  ASSERT_FALSE(s.id.empty());
  EXPECT_THROW(WsClient(server_->ws_port(), "/ws?session=" + s.id + "&token=" + s.token,
                        "http://127.0.0.1" + port_suffix(),
                        "203.0.113.7:" + std::to_string(server_->ws_port())),
               std::runtime_error);
  WsClient ok(server_->ws_port(), "/ws?session=" + s.id + "&token=" + s.token, origin());
}

TEST_F(WildcardTest, CreatingAndListingSessionsNeedTheServerKey) {
  auto c = http();
  for (const httplib::Headers& h :
       {httplib::Headers{{"Origin", origin()}},
        httplib::Headers{{"Origin", origin()}, {"X-Server-Key", std::string(32, '0')}}}) {
    const auto res =
        c.Post("/api/sessions", h, json{{"character", "human48"}}.dump(), "application/json");
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 401);
    EXPECT_NE(res->body.find("X-Server-Key"), std::string::npos);
  }
  EXPECT_EQ(c.Get("/api/sessions")->status, 401);
  EXPECT_EQ(c.Get("/api/sessions", with_key({}))->status, 200);
  EXPECT_FALSE(create_session("human48", with_key({})).id.empty());
  EXPECT_NE(server_->url().find("key=" + server_->server_key()), std::string::npos);
  // the key is kept, so the printed URL still works after a restart
  const std::string key = server_->server_key();
  restart();
  EXPECT_EQ(server_->server_key(), key);
  const auto config = http().Get("/api/config");
  ASSERT_TRUE(config);
  EXPECT_TRUE(json::parse(config->body).at("create_needs_key").get<bool>());
}

}  // namespace
