// Integration tests of the session store behind the server: creation is never refused for the
// number of stored sessions (also after a restart), idle sessions leave memory and come back
// with their edits, the list and DELETE routes, and expiry of untouched sessions.
#include "tests/server/server_fixture.hpp"

#include <chrono>
#include <set>

namespace {

using server_test::json;
using server_test::ServerTest;
using server_test::WsClient;
namespace fs = std::filesystem;

// Files of the data folder that belong to session `id`.
std::vector<fs::path> files_of(const fs::path& data, const std::string& id) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(data / "sessions")) {
    if (e.path().filename().string().rfind(id + ".", 0) == 0) out.push_back(e.path());
  }
  return out;
}

class StoreTest : public ServerTest {
 protected:
  void configure(server::ServerOptions& o) override {
    o.max_live_sessions = max_live_;
    o.expire_days = expire_days_;
  }
  json list() {
    auto c = http();
    const auto res = c.Get("/api/sessions");
    EXPECT_TRUE(res);
    if (!res) return json::array();
    EXPECT_EQ(res->status, 200) << res->body;
    return json::parse(res->body);
  }
  httplib::Result remove(const Created& s, const std::string& token) {
    auto c = http();
    return c.Delete("/api/sessions/" + s.id, {{"X-Session-Token", token}, {"Origin", origin()}});
  }
  void edit(const Created& s) {
    auto ws = connect(s);
    ws->read_until("snapshot");
    request(*ws, {{"type", "pin"}, {"link", "l_foot"}, {"mode", "pose"}}, 1);
    request(*ws, {{"type", "key_insert"}, {"time", 0.5}, {"interpolation", "step"}}, 2);
    ws->close();
  }
  // Waits until the server holds no more than `n` sessions in memory.
  bool live_at_most(std::size_t n) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (server_->registry().live() > n) {
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
  }
  fs::path data() const { return base_ / "data"; }

  std::size_t max_live_ = server::RegistryOptions::kDefaultMaxLive;
  int expire_days_ = 0;
};

TEST_F(StoreTest, ThreeHundredCreationsAreNeverRefusedAlsoAfterARestart) {
  std::set<std::string> ids;
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 300; ++i) {
    const Created s = create_session();
    ASSERT_FALSE(s.id.empty()) << "creation " << i << " refused";
    ids.insert(s.id);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "300 creations: " << seconds * 1e3 / 300 << " ms each, "
            << server_->registry().live() << " live\n";
  EXPECT_EQ(ids.size(), 300u);
  EXPECT_EQ(server_->registry().size(), 300u);
  EXPECT_LE(server_->registry().live(), server::RegistryOptions::kDefaultMaxLive);

  restart();
  EXPECT_EQ(server_->restored_sessions(), 300);
  EXPECT_EQ(server_->registry().live(), 0u) << "a restart loads sessions on demand only";
  for (int i = 0; i < 5; ++i) ASSERT_FALSE(create_session().id.empty());
  EXPECT_EQ(list().size(), 305u);
}

TEST_F(StoreTest, AnEvictedSessionComesBackWithItsEdits) {
  max_live_ = 2;
  restart();
  const Created a = create_session();
  edit(a);
  const json before = snapshot(a);
  ASSERT_EQ(before.at("pins").size(), 1u);
  ASSERT_EQ(before.at("keys").size(), 1u);

  // two newer sessions: the least recently used idle one (a) leaves memory
  const Created b = create_session();
  const Created c = create_session();
  ASSERT_TRUE(live_at_most(2));
  for (const json& row : list()) {
    if (row.at("id") == a.id) {
      EXPECT_FALSE(row.at("live").get<bool>());
    }
  }

  // ... and comes back from disk when asked for, over HTTP and over the WebSocket
  const json after = snapshot(a);
  EXPECT_EQ(after.at("pins"), before.at("pins"));
  EXPECT_EQ(after.at("keys"), before.at("keys"));
  EXPECT_EQ(after.at("q"), before.at("q"));
  // (the undo history stays in memory: it is not part of the session file, as after a restart)
  auto ws = connect(a);
  EXPECT_EQ(ws->read_until("snapshot").at("keys"), before.at("keys"));
  EXPECT_LE(server_->registry().live(), 2u);
  (void)b;
  (void)c;
}

TEST_F(StoreTest, SessionsInUseStayLiveAndAFullCacheIsATemporary503) {
  max_live_ = 2;
  restart();
  const Created a = create_session();
  auto ws_a = connect(a);
  ws_a->read_until("snapshot");
  const Created b = create_session();
  auto ws_b = connect(b);
  ws_b->read_until("snapshot");

  // both live sessions have a page open: no room, and the answer says when to come back
  auto c = http();
  const auto refused = c.Post("/api/sessions", {{"Origin", origin()}},
                              json{{"character", "human48"}}.dump(), "application/json");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503) << refused->body;
  EXPECT_FALSE(refused->get_header_value("Retry-After").empty());
  EXPECT_NE(json::parse(refused->body).at("error").get<std::string>().find("--max-live-sessions"),
            std::string::npos);

  // a page closes: its session may leave memory, and creating works again
  ws_b->close();
  ws_b.reset();
  Created d;
  for (int attempt = 0; attempt < 100 && d.id.empty(); ++attempt) {
    const auto res = c.Post("/api/sessions", {{"Origin", origin()}},
                            json{{"character", "human48"}}.dump(), "application/json");
    ASSERT_TRUE(res);
    if (res->status == 201)
      d.id = json::parse(res->body).at("id");
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_FALSE(d.id.empty());
  // the open page still works on its live session
  request(*ws_a, {{"type", "pin"}, {"link", "r_foot"}}, 7);
}

TEST_F(StoreTest, ListShowsStoredSessionsWithoutTokens) {
  const Created a = create_session();
  const Created b = create_session();
  const json rows = list();
  ASSERT_EQ(rows.size(), 2u);
  for (const json& row : rows) {
    EXPECT_TRUE(row.at("id") == a.id || row.at("id") == b.id);
    EXPECT_EQ(row.at("character"), "human48");
    EXPECT_GT(row.at("bytes").get<std::uint64_t>(), 1000u);
    EXPECT_GT(row.at("modified").get<std::int64_t>(), 1'600'000'000);
    EXPECT_FALSE(row.contains("token"));
    EXPECT_EQ(row.dump().find(a.token), std::string::npos);
  }
}

TEST_F(StoreTest, DeleteRemovesTheFilesAndRefusesABadTokenOrOrigin) {
  const Created s = create_session();
  const Created other = create_session();
  ASSERT_FALSE(files_of(data(), s.id).empty());

  auto res = remove(s, std::string(32, 'a'));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 401);
  res = remove(s, "");
  EXPECT_EQ(res->status, 401);
  auto c = http();
  res = c.Delete("/api/sessions/" + s.id,
                 {{"X-Session-Token", s.token}, {"Origin", "http://evil.example"}});
  EXPECT_EQ(res->status, 403);
  EXPECT_FALSE(files_of(data(), s.id).empty()) << "a refused delete removed files";
  EXPECT_EQ(snapshot(s).at("character").at("name"), "human48");

  // open in a page: refused, nothing lost
  {
    auto ws = connect(s);
    ws->read_until("snapshot");
    res = remove(s, s.token);
    EXPECT_EQ(res->status, 409) << res->body;
  }
  // closed: deleted, files and all
  for (int attempt = 0; attempt < 100; ++attempt) {
    res = remove(s, s.token);
    if (res->status != 409) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(res->status, 200) << res->body;
  EXPECT_TRUE(files_of(data(), s.id).empty());
  EXPECT_EQ(c.Get("/api/sessions/" + s.id, {{"X-Session-Token", s.token}})->status, 404);
  EXPECT_EQ(remove(s, s.token)->status, 404);
  const json rows = list();
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].at("id"), other.id);

  restart();
  EXPECT_EQ(server_->restored_sessions(), 1);
}

TEST_F(StoreTest, ExpiryDeletesSessionsUntouchedForLongerThanTheLimit) {
  const Created old_one = create_session();
  const Created fresh = create_session();
  expire_days_ = 7;
  server_.reset();
  // ten days without a save or an open
  const auto ten_days_ago = fs::file_time_type::clock::now() - std::chrono::hours(24 * 10);
  for (const fs::path& f : files_of(data(), old_one.id)) fs::last_write_time(f, ten_days_ago);
  start();
  EXPECT_EQ(server_->restored_sessions(), 1);
  EXPECT_TRUE(files_of(data(), old_one.id).empty());
  EXPECT_FALSE(files_of(data(), fresh.id).empty());
  auto c = http();
  EXPECT_EQ(c.Get("/api/sessions/" + old_one.id, {{"X-Session-Token", old_one.token}})->status,
            404);
  EXPECT_EQ(snapshot(fresh).at("character").at("name"), "human48");
}

}  // namespace
