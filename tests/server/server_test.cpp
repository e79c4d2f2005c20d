// Integration tests of the server (server/server.hpp) over real sockets on ephemeral loopback
// ports: the protocol end to end, the drag burst, reconnect and restart, and the security corpus.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <thread>

#include "core/bounds.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "io/gltf.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/server/actor_hold.hpp"
#include "tests/server/server_fixture.hpp"

namespace {

using server_test::json;
using server_test::ServerTest;
using server_test::WsClient;
namespace fs = std::filesystem;

TEST_F(ServerTest, HealthConfigAndCharacters) {
  auto c = http();
  auto res = c.Get("/api/health");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(json::parse(res->body).at("status"), "ok");

  res = c.Get("/api/config");
  ASSERT_TRUE(res);
  const json config = json::parse(res->body);
  EXPECT_EQ(config.at("protocol"), 1);
  EXPECT_EQ(config.at("ws_url"), "ws://127.0.0.1:" + std::to_string(server_->ws_port()) + "/ws");
  EXPECT_EQ(config.at("limits").at("upload_bytes"), 64 << 20);
  EXPECT_EQ(config.at("limits").at("ws_message_bytes"), 1 << 20);

  res = c.Get("/api/characters");
  ASSERT_TRUE(res);
  bool has_human = false;
  for (const json& ch : json::parse(res->body)) has_human = has_human || ch.at("name") == "human48";
  EXPECT_TRUE(has_human);

  res = c.Get("/");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_NE(res->body.find("pindrag"), std::string::npos);
  res = c.Get("/vendor/three/build/three.module.js");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->get_header_value("Content-Type").rfind("text/javascript", 0), 0u);
}

TEST_F(ServerTest, SnapshotOverHttpNeedsTheToken) {
  const Created s = create_session();
  const json snap = snapshot(s);
  EXPECT_EQ(snap.at("character").at("name"), "human48");
  const json& links = snap.at("links");
  ASSERT_EQ(links.size(), snap.at("character").at("links").size());
  ASSERT_GT(links.size(), 10u);
  EXPECT_EQ(links[0].at("p").size(), 3u);
  EXPECT_TRUE(snap.contains("pins") && snap.contains("keys") && snap.contains("clip") &&
              snap.contains("settings"));

  auto c = http();
  auto res = c.Get("/api/sessions/" + s.id);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 401);
  EXPECT_TRUE(json::parse(res->body).contains("error"));
  res = c.Get("/api/sessions/" + s.id, {{"X-Session-Token", std::string(32, 'a')}});
  EXPECT_EQ(res->status, 401);
  res = c.Get("/api/sessions/" + std::string(32, 'b'), {{"X-Session-Token", s.token}});
  EXPECT_EQ(res->status, 404);
  res = c.Post("/api/sessions", {{"Origin", origin()}}, R"({"character": "/etc/passwd"})",
               "application/json");
  EXPECT_EQ(res->status, 400);
  EXPECT_NE(json::parse(res->body).at("error").get<std::string>().find("character"),
            std::string::npos);
}

TEST_F(ServerTest, ProtocolEndToEnd) {
  const Created s = create_session();
  auto ws = connect(s);
  const json snap = ws->read_until("snapshot");
  EXPECT_EQ(snap.at("session"), s.id);
  EXPECT_EQ(snap.at("protocol"), 1);
  const json& links = snap.at("links");

  // the first pose frame agrees with the snapshot
  server_test::PoseFrame pose;
  for (;;) {
    const auto m = ws->read();
    if (!m.text) {
      pose = server_test::decode_pose(m.data);
      break;
    }
  }
  EXPECT_EQ(pose.magic, server::kPoseMagic);
  EXPECT_EQ(pose.version, 1);
  ASSERT_EQ(pose.links, links.size());
  EXPECT_EQ(pose.last_seq, 0u);
  for (size_t i = 0; i < links.size(); ++i) {
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(pose.values[i][k], links[i].at("p")[k].get<double>(), 1e-5);
  }

  int hand = -1;
  for (size_t i = 0; i < links.size(); ++i) {
    if (links[i].at("name") == "r_hand") hand = static_cast<int>(i);
  }
  ASSERT_GE(hand, 0);
  std::array<double, 3> start{};
  for (int k = 0; k < 3; ++k) start[k] = links[hand].at("p")[k];

  request(*ws, {{"type", "pin"}, {"link", "l_foot"}, {"mode", "pose"}}, 1);
  const json state = ws->read_until("state");
  ASSERT_EQ(state.at("pins").size(), 1u);
  EXPECT_EQ(state.at("pins")[0].at("link"), "l_foot");
  EXPECT_EQ(state.at("pins")[0].at("mode"), "pose");

  // drag the right hand 10 cm forward and up
  const std::array<double, 3> goal{start[0], start[1] + 0.1, start[2] + 0.1};
  request(*ws, {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", start}}, 2);
  for (std::uint32_t seq = 1; seq <= 30; ++seq) {
    const double a = seq / 30.0;
    ws->send({{"type", "drag_move"},
              {"seq", seq},
              {"target", {start[0], start[1] + 0.1 * a, start[2] + 0.1 * a}}});
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // poses keep coming while the solver settles; wait until the hand is close to the goal
  double distance = 1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (distance > 0.01 && std::chrono::steady_clock::now() < deadline) {
    const auto m = ws->read();
    if (m.text) continue;
    pose = server_test::decode_pose(m.data);
    if (pose.last_seq != 30) continue;
    distance = std::hypot(pose.values[hand][0] - goal[0], pose.values[hand][1] - goal[1],
                          pose.values[hand][2] - goal[2]);
  }
  EXPECT_LT(distance, 0.01) << "the hand did not reach the drag target";
  request(*ws, {{"type", "drag_end"}}, 3);
  request(*ws, {{"type", "key_insert"}, {"time", 0.5}, {"interpolation", "linear"}}, 4);
  json after_key = ws->read_until("state");
  ASSERT_EQ(after_key.at("keys").size(), 1u);
  EXPECT_EQ(after_key.at("keys")[0].at("interpolation"), "linear");
  request(*ws, {{"type", "undo"}}, 5);
  EXPECT_EQ(ws->read_until("state").at("keys").size(), 0u);
  request(*ws, {{"type", "redo"}}, 6);
  EXPECT_EQ(ws->read_until("state").at("keys").size(), 1u);
  request(*ws, {{"type", "set_settings"}, {"settings", {{"iterations", 3}}}}, 7);

  // refusals name the field and leave the session as it was
  ws->send({{"type", "pin"}, {"link", "tail"}, {"id", 8}});
  json error = ws->read_until("error");
  EXPECT_EQ(error.at("id"), 8);
  EXPECT_NE(error.at("message").get<std::string>().find("pin.link"), std::string::npos)
      << error.dump();
  ws->send({{"type", "drag_move"}, {"seq", 31}, {"target", {0, "x", 0}}, {"id", 9}});
  error = ws->read_until("error");
  EXPECT_EQ(error.at("id"), 9);
  EXPECT_NE(error.at("message").get<std::string>().find("drag_move.target"), std::string::npos);
  ws->send({{"type", "teleport"}, {"id", 10}});
  EXPECT_NE(ws->read_until("error").at("message").get<std::string>().find("teleport"),
            std::string::npos);

  // export of the keyed animation
  auto c = http();
  auto res = c.Get("/api/sessions/" + s.id + "/export?format=bvh", {{"X-Session-Token", s.token}});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->body.rfind("HIERARCHY", 0), 0u);
  EXPECT_NE(
      res->get_header_value("Content-Disposition").find("attachment; filename=\"human48.bvh\""),
      std::string::npos);
  res = c.Get("/api/sessions/" + s.id + "/export?format=glb", {{"X-Session-Token", s.token}});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->body.substr(0, 4), "glTF");
  res = c.Get("/api/sessions/" + s.id + "/export?format=obj", {{"X-Session-Token", s.token}});
  EXPECT_EQ(res->status, 400);
}

TEST_F(ServerTest, ThumbnailIsAPngOfTheAskedSize) {
  const Created s = create_session();
  auto c = http();
  auto res =
      c.Get("/api/sessions/" + s.id + "/thumbnail.png?size=64", {{"X-Session-Token", s.token}});
  ASSERT_TRUE(res);
  if (res->status == 501) GTEST_SKIP() << "built without the thumbnail renderer";
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "image/png");
  ASSERT_GT(res->body.size(), 24u);
  EXPECT_EQ(res->body.substr(1, 3), "PNG");
  // IHDR width and height, big-endian at bytes 16..23
  auto be32 = [&](size_t at) {
    return (static_cast<unsigned char>(res->body[at]) << 24) |
           (static_cast<unsigned char>(res->body[at + 1]) << 16) |
           (static_cast<unsigned char>(res->body[at + 2]) << 8) |
           static_cast<unsigned char>(res->body[at + 3]);
  };
  EXPECT_EQ(be32(16), 64);
  EXPECT_EQ(be32(20), 64);
  for (const std::string& bad :
       std::vector<std::string>{"size=8", "size=2000", "size=abc", "frame=5"}) {
    res = c.Get("/api/sessions/" + s.id + "/thumbnail.png?" + bad, {{"X-Session-Token", s.token}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 400) << bad;
  }
  res = c.Get("/api/sessions/" + s.id + "/thumbnail.png");
  EXPECT_EQ(res->status, 401);
}

TEST_F(ServerTest, ThousandDragMovesInOneBurstAreCoalescedAndAckedInOrder) {
  const Created s = create_session();
  auto ws = connect(s);
  const json snap = ws->read_until("snapshot");
  std::array<double, 3> start{};
  for (const json& l : snap.at("links")) {
    if (l.at("name") == "r_hand") {
      for (int k = 0; k < 3; ++k) start[k] = l.at("p")[k];
    }
  }
  request(*ws, {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", start}}, 0);
  const auto actor = actor_of(s);
  const server::ActorStats before = actor->stats();

  constexpr int kBurst = 1000;
  const auto t0 = std::chrono::steady_clock::now();
  for (int seq = 1; seq <= kBurst; ++seq) {
    const double a = 0.1 * seq / kBurst;
    ws->send({{"type", "drag_move"},
              {"seq", seq},
              {"id", seq},
              {"target", {start[0] + a, start[1], start[2] + a}}});
  }
  int next_ack = 1;
  std::uint32_t newest_seq_seen = 0;
  while (next_ack <= kBurst || newest_seq_seen < kBurst) {
    const auto m = ws->read();
    if (!m.text) {
      newest_seq_seen = std::max(newest_seq_seen, server_test::decode_pose(m.data).last_seq);
      continue;
    }
    const json j = m.json();
    if (j.at("type") == "error") FAIL() << j.dump();
    if (j.at("type") != "ack") continue;
    ASSERT_EQ(j.at("id"), next_ack) << "acks out of order";
    EXPECT_EQ(j.at("request"), "drag_move");
    ++next_ack;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const server::ActorStats after = actor->stats();
  const auto applied = after.drag_samples_applied - before.drag_samples_applied;
  const auto ticks = after.ticks - before.ticks;
  EXPECT_EQ(after.drag_samples_received - before.drag_samples_received,
            static_cast<unsigned>(kBurst));
  // How many samples wait for each step depends on how fast this build parses and solves, so the
  // solves are bounded by the actor's rule, not by a figure: sample ticks come at least
  // kMinTickInterval apart, periodic ones kTickPeriod. The held burst below checks the coalescing.
  const double tick_rate_limit =
      1.0 / std::chrono::duration<double>(server::SessionActor::kMinTickInterval).count() +
      1.0 / std::chrono::duration<double>(server::SessionActor::kTickPeriod).count();
  EXPECT_LE(static_cast<double>(ticks), seconds * tick_rate_limit + 2.0) << "ticks " << ticks;
  EXPECT_LT(seconds, 5.0);
  std::cout << "burst of " << kBurst << " drag_moves: " << applied << " applied, " << ticks
            << " ticks, " << seconds * 1e3 << " ms until the last ack\n";

  // The same burst while the actor is busy (a command holds it until every sample has arrived):
  // the superseded samples are dropped whatever the speed, and only the newest is applied.
  server_test::ActorHold hold(*actor);
  for (int seq = kBurst + 1; seq <= 2 * kBurst; ++seq) {
    const double a = 0.1 * (2 * kBurst - seq) / kBurst;
    ws->send({{"type", "drag_move"},
              {"seq", seq},
              {"id", seq},
              {"target", {start[0] + a, start[1], start[2] + a}}});
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (actor->stats().drag_samples_received - before.drag_samples_received <
             static_cast<unsigned>(2 * kBurst) &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  hold.release();
  while (next_ack <= 2 * kBurst) {
    const auto m = ws->read();
    if (!m.text) continue;
    const json j = m.json();
    if (j.at("type") == "error") FAIL() << j.dump();
    if (j.at("type") != "ack") continue;
    ASSERT_EQ(j.at("id"), next_ack) << "acks out of order";
    ++next_ack;
  }
  const server::ActorStats held = actor->stats();
  EXPECT_EQ(held.drag_samples_received - after.drag_samples_received,
            static_cast<unsigned>(kBurst));
  EXPECT_EQ(held.drag_samples_applied - after.drag_samples_applied, 1u);
}

TEST_F(ServerTest, ReconnectRestoresPinsKeysAndLayers) {
  const Created s = create_session();
  json last_state;
  {
    auto ws = connect(s);
    const json snap = ws->read_until("snapshot");
    std::array<double, 3> hand{};
    for (const json& l : snap.at("links")) {
      if (l.at("name") == "r_hand") {
        for (int k = 0; k < 3; ++k) hand[k] = l.at("p")[k];
      }
    }
    request(*ws, {{"type", "pin"}, {"link", "l_foot"}, {"mode", "position"}}, 1);
    request(*ws, {{"type", "key_insert"}, {"time", 0.0}}, 2);
    request(*ws, {{"type", "key_insert"}, {"time", 1.0}}, 3);
    request(*ws, {{"type", "bake_keys"}, {"rate", 30}}, 4);
    request(*ws, {{"type", "key_insert"}, {"time", 0.5}}, 5);
    // an edit during playback becomes a layer
    request(*ws, {{"type", "play"}}, 6);
    request(*ws, {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", hand}}, 7);
    for (std::uint32_t seq = 1; seq <= 10; ++seq) {
      ws->send({{"type", "drag_move"},
                {"seq", seq},
                {"target", {hand[0], hand[1] + 0.01 * seq, hand[2]}}});
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    request(*ws, {{"type", "drag_end"}}, 8);
    request(*ws, {{"type", "pause"}}, 9);
    request(*ws, {{"type", "undo"}}, 10);  // the undo history is part of what comes back too
    request(*ws, {{"type", "redo"}}, 11);
    last_state = ws->read_until("state");
    ws->close();
  }
  ASSERT_EQ(last_state.at("pins").size(), 1u);
  ASSERT_GE(last_state.at("keys").size(), 1u);
  ASSERT_GE(last_state.at("layers").size(), 1u) << "the drag during playback made no layer";

  auto ws = connect(s);
  const json again = ws->read_until("snapshot");
  EXPECT_EQ(again.at("pins"), last_state.at("pins"));
  EXPECT_EQ(again.at("keys"), last_state.at("keys"));
  EXPECT_EQ(again.at("layers"), last_state.at("layers"));
  EXPECT_EQ(again.at("clip"), last_state.at("clip"));
  EXPECT_EQ(again.at("undo"), last_state.at("undo"));
}

TEST_F(ServerTest, RestartRestoresSessions) {
  const Created s = create_session();
  {
    auto ws = connect(s);
    ws->read_until("snapshot");
    request(*ws, {{"type", "pin"}, {"link", "l_foot"}, {"mode", "pose"}}, 1);
    request(*ws, {{"type", "key_insert"}, {"time", 0.25}, {"interpolation", "step"}}, 2);
    ws->close();
  }
  const json before = snapshot(s);
  restart();
  EXPECT_EQ(server_->restored_sessions(), 1);
  const json after = snapshot(s);
  EXPECT_EQ(after.at("pins"), before.at("pins"));
  EXPECT_EQ(after.at("keys"), before.at("keys"));
  EXPECT_EQ(after.at("q"), before.at("q"));
  auto ws = connect(s);
  EXPECT_EQ(ws->read_until("snapshot").at("pins").size(), 1u);
}

TEST_F(ServerTest, BadHostIsRefused) {
  auto c = http();
  for (const std::string& host : std::vector<std::string>{
           "evil.example", "evil.example:" + std::to_string(server_->http_port()), "127.0.0.1:1",
           "localhost.evil.example:" + std::to_string(server_->http_port())}) {
    const auto res = c.Get("/api/health", {{"Host", host}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 403) << host;
    EXPECT_TRUE(json::parse(res->body).contains("error"));
  }
  const auto ok =
      c.Get("/api/health", {{"Host", "localhost:" + std::to_string(server_->http_port())}});
  EXPECT_EQ(ok->status, 200);
  // the WebSocket checks the Host of its own port
  const Created s = create_session();
  EXPECT_THROW(WsClient(server_->ws_port(), "/ws?session=" + s.id + "&token=" + s.token, origin(),
                        "evil.example"),
               std::runtime_error);
}

TEST_F(ServerTest, EvilOriginIsRefused) {
  const Created s = create_session();
  const std::string target = "/ws?session=" + s.id + "&token=" + s.token;
  for (const std::string& evil :
       std::vector<std::string>{"http://evil.example", "null", origin() + ".evil.example",
                                "https://127.0.0.1:" + std::to_string(server_->http_port())}) {
    try {
      WsClient ws(server_->ws_port(), target, evil);
      ADD_FAILURE() << "upgrade accepted with Origin " << evil;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("status 403"), std::string::npos) << e.what();
    }
  }
  try {
    WsClient ws(server_->ws_port(), "/ws?session=" + s.id + "&token=" + std::string(32, '0'),
                origin());
    ADD_FAILURE() << "upgrade accepted with a wrong token";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("status 401"), std::string::npos) << e.what();
  }
  auto c = http();
  const auto res = c.Post("/api/sessions", {{"Origin", "http://evil.example"}},
                          R"({"character": "human48"})", "application/json");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 403);
  // the right Origin and token connect
  WsClient ws(server_->ws_port(), target, origin());
}

TEST_F(ServerTest, PathTraversalCorpusGets4xx) {
  const std::string host = "Host: 127.0.0.1:" + std::to_string(server_->http_port()) + "\r\n";
  for (const std::string& path : std::vector<std::string>{
           "/../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/..%2f..%2fetc%2fpasswd",
           "/%2e%2e%2f%2e%2e%2fetc/passwd", "/%5c..%5c..%5cetc%5cpasswd",
           "/js%5c..%5c..%5csecret.txt", "//etc/passwd", "/js/../../secret.txt",
           "/js/%2e%2e/%2e%2e/secret.txt", "/link_out.txt", "/node_modules/three/package.json",
           "/vendor/three/package.json", "/vendor/three/build/../../../secret.txt",
           "/vendor/three/build/%2e%2e/%2e%2e/%2e%2e/secret.txt", "/.git/config", "/%00index.html",
           "/etc/passwd", "/" + fs::absolute(base_ / "secret.txt").string(), "../secret.txt"}) {
    const auto reply = server_test::raw_http(
        server_->http_port(), "GET " + path + " HTTP/1.1\r\n" + host + "Connection: close\r\n\r\n");
    EXPECT_GE(reply.status, 400) << path;
    EXPECT_LT(reply.status, 500) << path;
    EXPECT_EQ(reply.body.find("root:"), std::string::npos) << path;
    EXPECT_EQ(reply.body.find("secret"), std::string::npos) << path;
  }
  auto c = http();
  EXPECT_EQ(c.Get("/api/health")->status, 200);
}

TEST_F(ServerTest, OversizeUploadGets413) {
  const Created s = create_session();
  httplib::MultipartFormDataItems items{
      {"clip", std::string((std::size_t{64} << 20) + (std::size_t{1} << 20), 'x'), "huge.bvh",
       "application/octet-stream"}};
  auto c = http();
  const auto res = c.Post("/api/sessions/" + s.id + "/clip",
                          {{"X-Session-Token", s.token}, {"Origin", origin()}}, items);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 413);
  // a small upload that is not a BVH is a 4xx naming the field
  httplib::MultipartFormDataItems bad{
      {"clip", "HIERARCHY\nROOT x {\n", "broken.bvh", "text/plain"}};
  const auto res2 = c.Post("/api/sessions/" + s.id + "/clip",
                           {{"X-Session-Token", s.token}, {"Origin", origin()}}, bad);
  ASSERT_TRUE(res2);
  EXPECT_EQ(res2->status, 422);
  EXPECT_NE(json::parse(res2->body).at("error").get<std::string>().find("clip"), std::string::npos);
  EXPECT_EQ(c.Get("/api/health")->status, 200);
}

// "Load clip…" with a marker trial: fitted onto the human figure with its bundled marker set,
// it becomes the session's clip; a character without a marker set and a broken file are 422s
// naming the rule or the field, and the session keeps what it had.
TEST_F(ServerTest, AMarkerTrialUploadIsFittedOntoTheHumanFigure) {
  PINDRAG_REQUIRE_DATA_DIR();
  std::ifstream file(fixtures::data_dir() + "/c3d/cmu_85_02.c3d", std::ios::binary);
  const std::string trial((std::istreambuf_iterator<char>(file)), {});
  ASSERT_GT(trial.size(), 512u);
  auto c = http();
  const auto upload = [&](const Created& s, const std::string& bytes, const std::string& name) {
    const httplib::MultipartFormDataItems items{{"clip", bytes, name, "application/octet-stream"}};
    return c.Post("/api/sessions/" + s.id + "/clip",
                  {{"X-Session-Token", s.token}, {"Origin", origin()}}, items);
  };
  const Created s = create_session("human48");
  const auto fitted = upload(s, trial, "cmu_85_02.c3d");
  ASSERT_TRUE(fitted);
  ASSERT_EQ(fitted->status, 200) << fitted->body;
  EXPECT_EQ(json::parse(fitted->body).at("frames"), 810);
  const json snap = snapshot(s);
  EXPECT_EQ(snap.at("clip").at("frames"), 810);
  EXPECT_NEAR(snap.at("clip").at("frame_time").get<double>(), 1.0 / 120, 1e-9);
  // a truncated trial: the field and the C3D rule are named, the fitted clip stays
  const auto broken = upload(s, trial.substr(0, 300), "short.c3d");
  ASSERT_TRUE(broken);
  EXPECT_EQ(broken->status, 422);
  const std::string why = json::parse(broken->body).at("error");
  EXPECT_NE(why.find("clip: short.c3d: header"), std::string::npos) << why;
  EXPECT_EQ(snapshot(s).at("clip").at("frames"), 810);
  // a robot arm has no marker set
  const Created arm = create_session("arm7");
  const auto refused = upload(arm, trial, "cmu_85_02.c3d");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 422);
  const std::string rule = json::parse(refused->body).at("error");
  EXPECT_NE(rule.find("no marker set for the character 'arm7'"), std::string::npos) << rule;
  EXPECT_EQ(c.Get("/api/health")->status, 200);
}

// The measured markers of a fitted trial are served beside its clip (GET .../markers): in the
// world frame of the snapshot's links, so that each lies near its virtual marker (link pose times
// calibrated offset) in the frame shown; revalidated by revision; gone with undo, back with redo.
TEST_F(ServerTest, AFittedTrialsMarkersAreServedBesideItsClip) {
  PINDRAG_REQUIRE_DATA_DIR();
  std::ifstream file(fixtures::data_dir() + "/c3d/cmu_85_02.c3d", std::ios::binary);
  const std::string trial((std::istreambuf_iterator<char>(file)), {});
  auto c = http();
  const Created s = create_session("human48");
  const httplib::Headers auth{{"X-Session-Token", s.token}, {"Origin", origin()}};
  EXPECT_EQ(c.Get("/api/sessions/" + s.id + "/markers", auth)->status, 404);
  const httplib::MultipartFormDataItems items{
      {"clip", trial, "cmu_85_02.c3d", "application/octet-stream"}};
  const auto fitted = c.Post("/api/sessions/" + s.id + "/clip", auth, items);
  ASSERT_TRUE(fitted);
  ASSERT_EQ(fitted->status, 200) << fitted->body;
  EXPECT_EQ(json::parse(fitted->body).at("markers"), 41);

  const json snap = snapshot(s);
  const json& summary = snap.at("markers");
  EXPECT_EQ(summary.at("count"), 41);
  EXPECT_EQ(summary.at("frames"), 810);
  EXPECT_EQ(summary.at("rate"), 120.0);
  const auto got = c.Get("/api/sessions/" + s.id + "/markers", auth);
  ASSERT_TRUE(got);
  ASSERT_EQ(got->status, 200) << got->body;
  const json markers = json::parse(got->body);
  EXPECT_EQ(markers.at("revision"), summary.at("revision"));
  ASSERT_EQ(markers.at("markers").size(), 41u);
  ASSERT_EQ(markers.at("frames").size(), 810u);

  // the frame shown (time 0): each seen marker against link pose × offset
  const double time = snap.at("playback").at("time");
  const auto frame = static_cast<std::size_t>(std::lround(time * 120.0));
  const json& row = markers.at("frames").at(frame);
  std::map<std::string, json> links;
  for (const json& l : snap.at("links")) links[l.at("name")] = l;
  double sum = 0, worst = 0;
  int seen = 0;
  for (std::size_t k = 0; k < 41; ++k) {
    if (row.at(3 * k).is_null()) continue;
    const json& m = markers.at("markers").at(k);
    const json& link = links.at(m.at("link").get<std::string>());
    const Eigen::Vector3d p(link.at("p")[0], link.at("p")[1], link.at("p")[2]);
    const Eigen::Quaterniond R(link.at("R")[0], link.at("R")[1], link.at("R")[2], link.at("R")[3]);
    const Eigen::Vector3d offset(m.at("offset")[0], m.at("offset")[1], m.at("offset")[2]);
    const Eigen::Vector3d measured(row.at(3 * k), row.at(3 * k + 1), row.at(3 * k + 2));
    const double r = (measured - (p + R * offset)).norm();
    sum += r;
    worst = std::max(worst, r);
    ++seen;
  }
  ASSERT_GT(seen, 30);
  // (the whole trial fits to 16 mm on average, every marker's mean under 40 mm)
  EXPECT_LT(sum / seen, 0.03) << "the markers are not where the figure's markers are";
  EXPECT_LT(worst, 0.1);

  // revalidated by revision
  httplib::Headers again = auth;
  again.emplace("If-None-Match", got->get_header_value("ETag"));
  EXPECT_EQ(c.Get("/api/sessions/" + s.id + "/markers", again)->status, 304);

  // undo takes the fitted clip and its markers away; redo brings both back
  auto ws = connect(s);
  ws->read_until("snapshot");
  request(*ws, {{"type", "undo"}}, 1);
  EXPECT_TRUE(ws->read_until("state").at("markers").is_null());
  EXPECT_EQ(c.Get("/api/sessions/" + s.id + "/markers", auth)->status, 404);
  request(*ws, {{"type", "redo"}}, 2);
  EXPECT_EQ(ws->read_until("state").at("markers").at("revision"), summary.at("revision"));
  EXPECT_EQ(c.Get("/api/sessions/" + s.id + "/markers", again)->status, 304);
}

// A clip of another skeleton: the page asks for the correspondence retargeting would guess, the
// user edits it, and the upload retargets with their mapping; a mapping that names a link the
// character lacks, or is not JSON, is a 422 naming it, and the session keeps its clip.
TEST_F(ServerTest, RetargetingShowsItsGuessAndTakesTheUsersMapping) {
  PINDRAG_REQUIRE_DATA_DIR();
  std::ifstream file(fixtures::data_dir() + "/bvh/mixamo_naming_freebvh.bvh", std::ios::binary);
  const std::string clip((std::istreambuf_iterator<char>(file)), {});
  ASSERT_GT(clip.size(), 100u);
  auto c = http();
  const Created s = create_session("human48");
  const httplib::Headers auth{{"X-Session-Token", s.token}, {"Origin", origin()}};
  const auto post = [&](const std::string& path, const std::string& mapping) {
    httplib::MultipartFormDataItems items{{"clip", clip, "walk.bvh", "application/octet-stream"}};
    if (!mapping.empty()) items.push_back({"mapping", mapping, "mapping.json", "application/json"});
    return c.Post("/api/sessions/" + s.id + path, auth, items);
  };

  const auto guess = post("/clip/correspondence", "");
  ASSERT_TRUE(guess);
  ASSERT_EQ(guess->status, 200) << guess->body;
  const json g = json::parse(guess->body);
  EXPECT_EQ(g.at("same_skeleton"), false);
  EXPECT_EQ(g.at("source_convention"), "mixamo");
  std::map<std::string, json> target_of;
  for (const json& j : g.at("joints")) target_of[j.at("source")] = j.at("target");
  EXPECT_EQ(target_of.at("mixamorig:LeftHand"), "l_hand");
  EXPECT_EQ(target_of.at("mixamorig:Hips"), "pelvis");
  EXPECT_NE(std::find(g.at("links").begin(), g.at("links").end(), "r_hand"), g.at("links").end());
  EXPECT_TRUE(snapshot(s).at("clip").is_null()) << "asking for the guess changed the session";

  // retargeted as guessed, then with the left arm left out: its joints stop following
  ASSERT_EQ(post("/clip?retarget=1", "")->status, 200);
  const json guessed = snapshot(s);
  const auto mapped = post("/clip?retarget=1", R"({"mixamorig:LeftArm": null,
      "mixamorig:LeftForeArm": null, "mixamorig:LeftHand": null})");
  ASSERT_TRUE(mapped);
  ASSERT_EQ(mapped->status, 200) << mapped->body;
  const json edited = snapshot(s);
  const auto link_of = [](const json& snap, const std::string& name) {
    for (const json& l : snap.at("links"))
      if (l.at("name") == name) return l;
    return json();
  };
  // the elbow's bend: the angle between upper arm and forearm
  const auto bend = [&](const json& snap, const std::string& side) {
    const auto q = [&](const std::string& name) {
      const json R = link_of(snap, name).at("R");
      return Eigen::Quaterniond(R[0], R[1], R[2], R[3]);
    };
    return q(side + "_uarm").angularDistance(q(side + "_farm"));
  };
  std::cout << "elbow bend at time 0, as guessed: left " << bend(guessed, "l") << ", right "
            << bend(guessed, "r") << "; left arm unmapped: left " << bend(edited, "l") << ", right "
            << bend(edited, "r") << " rad\n";
  EXPECT_GT(bend(guessed, "l"), 0.2) << "the clip's left elbow is not bent at time 0";
  EXPECT_LT(bend(edited, "l"), 0.1) << "the unmapped left elbow still bends with the clip";
  EXPECT_NEAR(bend(edited, "r"), bend(guessed, "r"), 0.05) << "the right elbow followed the edit";

  // a link the character does not have; text that is not JSON
  const auto unknown = post("/clip?retarget=1", R"({"mixamorig:LeftHand": "l_paw"})");
  ASSERT_TRUE(unknown);
  EXPECT_EQ(unknown->status, 422);
  const std::string why = json::parse(unknown->body).at("error");
  EXPECT_NE(why.find("mapping"), std::string::npos) << why;
  EXPECT_NE(why.find("l_paw"), std::string::npos) << why;
  const auto broken = post("/clip?retarget=1", "{\"mixamorig:LeftHand\": ");
  ASSERT_TRUE(broken);
  EXPECT_EQ(broken->status, 422);
  const std::string syntax = json::parse(broken->body).at("error");
  EXPECT_EQ(syntax.rfind("mapping: line 1", 0), 0u) << syntax;
  EXPECT_EQ(snapshot(s).at("links"), edited.at("links")) << "a refused mapping changed the clip";
}

// An animation saved without its mesh (a skeleton and its keys, as "without skin" downloads
// come) opens from the page as a character drawn with capsules, and loads as a clip onto another
// character through retargeting
TEST_F(ServerTest, AnAnimationWithoutItsMeshOpensAsACharacterAndRetargetsAsAClip) {
  const auto m = core::build_human_figure({});
  core::Clip clip;
  for (int k = 0; k < 10; ++k) clip.frames.push_back(core::random_configuration(*m, 100 + k));
  const std::vector<std::uint8_t> glb = io::write_glb(*m, &clip, nullptr, {});
  const std::string bytes(glb.begin(), glb.end());
  auto c = http();
  const auto opened = c.Post(
      "/api/sessions", {{"Origin", origin()}},
      httplib::MultipartFormDataItems{{"character", bytes, "walk.glb", "model/gltf-binary"}});
  ASSERT_TRUE(opened);
  ASSERT_EQ(opened->status, 201) << opened->body;
  const json created = json::parse(opened->body);
  const Created s{created.at("id"), created.at("token")};
  const json snap = snapshot(s);
  EXPECT_EQ(snap.at("character").at("skinned"), false);
  EXPECT_EQ(snap.at("character").at("links").size(), static_cast<std::size_t>(m->nlinks()));
  EXPECT_EQ(snap.at("clip").at("frames"), 10);
  const auto mesh = c.Get("/api/sessions/" + s.id + "/mesh", {{"X-Session-Token", s.token}});
  ASSERT_TRUE(mesh);
  EXPECT_EQ(mesh->status, 404);
  // as a clip of the human figure: its joints are other joints (spherical), so it is retargeted
  const Created human = create_session("human48");
  const auto loaded =
      c.Post("/api/sessions/" + human.id + "/clip?retarget=1",
             {{"X-Session-Token", human.token}, {"Origin", origin()}},
             httplib::MultipartFormDataItems{{"clip", bytes, "walk.glb", "model/gltf-binary"}});
  ASSERT_TRUE(loaded);
  ASSERT_EQ(loaded->status, 200) << loaded->body;
  EXPECT_EQ(snapshot(human).at("clip").at("frames"), 10);
}

// A figure saved with its pelvis at the origin (its legs under the floor) opens standing on the
// ground: every link straight up by the depth of the lowest point its mesh reaches over the clip.
// A BVH capture the same: its legs' end sites come up onto the floor.
TEST_F(ServerTest, AnUploadedFigureAndItsClipOpenStandingOnTheGround) {
  const auto m = core::build_human_figure({});
  core::Clip clip;
  double lowest = std::numeric_limits<double>::infinity();  // of the links' shapes, over the clip
  core::Data data(*m);
  for (int k = 0; k < 10; ++k) {
    // the first frame stands as the figure was built (facing +Z, so nothing turns it)
    Eigen::VectorXd q =
        k == 0 ? core::rest_configuration(*m) : core::random_configuration(*m, 300 + k);
    // the pelvis at height 0 (the root's placement stands the figure; its coordinates undo that),
    // walking along x
    q.head<3>() = m->X_PJ[1].R.transpose() * (core::Vector3(0.1 * k, 0, 0) - m->X_PJ[1].p);
    clip.frames.push_back(q);
    core::forward_kinematics(*m, data, q);
    lowest = std::min(lowest, core::world_bounds(*m, data).min.y());
  }
  ASSERT_LT(lowest, -0.5);
  core::forward_kinematics(*m, data, clip.frames[0]);
  // the links' shapes as the file's mesh (tessellated: its lowest point is within 2 mm of theirs)
  io::GltfExportOptions shapes;
  shapes.shape_mesh = true;
  const std::vector<std::uint8_t> glb = io::write_glb(*m, &clip, nullptr, shapes);
  auto c = http();
  const auto opened =
      c.Post("/api/sessions", {{"Origin", origin()}},
             httplib::MultipartFormDataItems{{"character", std::string(glb.begin(), glb.end()),
                                              "low.glb", "model/gltf-binary"}});
  ASSERT_TRUE(opened);
  ASSERT_EQ(opened->status, 201) << opened->body;
  const json created = json::parse(opened->body);
  const json snap = snapshot({created.at("id"), created.at("token")});
  EXPECT_EQ(snap.at("character").at("skinned"), true);
  int compared = 0;
  for (const json& link : snap.at("links")) {
    const int i = m->link_index(link.at("name").get<std::string>());
    if (i < 0) continue;
    const core::Vector3 p(link.at("p")[0], link.at("p")[1], link.at("p")[2]);
    const core::Vector3 expected = data.X_W[i].p + core::Vector3(0, -lowest, 0);
    EXPECT_LT((p - expected).norm(), 2e-3)
        << link.at("name") << ": " << p.transpose() << " expected " << expected.transpose();
    ++compared;
  }
  EXPECT_EQ(compared, m->nlinks());

  // a capture whose hips are at the origin and legs 0.9 m long
  const std::string bvh =
      "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n"
      " CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
      " JOINT LeftUpLeg\n {\n  OFFSET 10 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "  JOINT LeftLeg\n  {\n   OFFSET 0 -45 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "   End Site\n   {\n    OFFSET 0 -45 0\n   }\n  }\n }\n"
      " JOINT Spine\n {\n  OFFSET 0 10 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "  End Site\n  {\n   OFFSET 0 60 0\n  }\n }\n}\n"
      "MOTION\nFrames: 2\nFrame Time: 0.033333\n"
      "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n10 0 0 0 0 0 0 30 0 0 -20 0 0 0 0\n";
  const auto captured =
      c.Post("/api/sessions", {{"Origin", origin()}},
             httplib::MultipartFormDataItems{{"character", bvh, "low.bvh", "text/plain"}});
  ASSERT_TRUE(captured);
  ASSERT_EQ(captured->status, 201) << captured->body;
  const json made = json::parse(captured->body);
  double lowest_origin = std::numeric_limits<double>::infinity();
  const json captured_snap = snapshot({made.at("id"), made.at("token")});
  for (const json& link : captured_snap.at("links"))
    lowest_origin = std::min(lowest_origin, link.at("p")[1].get<double>());
  // the foot's end site was 0.9 m under the floor; now above it by no more than a capsule radius
  EXPECT_GE(lowest_origin, 0.0);
  EXPECT_LT(lowest_origin, 0.1);
}

TEST_F(ServerTest, OversizeMessageClosesWith1009) {
  const Created s = create_session();
  auto ws = connect(s);
  ws->read_until("snapshot");
  ws->send_text(std::string((std::size_t{1} << 20) + 1, ' '));
  bool closed = false;
  try {
    for (int k = 0; k < 1000; ++k) ws->read();
  } catch (const std::runtime_error&) {
    closed = true;
  }
  EXPECT_TRUE(closed);
  EXPECT_EQ(ws->close_code(), 1009);
  // the server goes on
  auto again = connect(s);
  EXPECT_EQ(again->read_until("snapshot").at("session"), s.id);
}

TEST_F(ServerTest, MalformedMessagesGetErrorsAndTheServerSurvives) {
  const Created s = create_session();
  auto ws = connect(s);
  ws->read_until("snapshot");
  for (const std::string& text :
       std::vector<std::string>{"{", "[]", "42", "{\"type\": 7}", "{\"no_type\": 1}",
                                "{\"type\": \"drag_move\", \"seq\": -1, \"target\": [0, 0, 0]}",
                                "{\"type\": \"pin\", \"link\": \"l_foot\", \"mode\": \"glue\"}",
                                "{\"type\": \"seek\", \"time\": 1e400}"}) {
    ws->send_text(text);
    const json error = ws->read_until("error");
    EXPECT_FALSE(error.at("message").get<std::string>().empty()) << text;
  }
  ws->send_binary(std::string("PDPF\x01\x00\xff\xff", 8));
  EXPECT_NE(ws->read_until("error").at("message").get<std::string>().find("binary"),
            std::string::npos);
  // the connection still works
  request(*ws, {{"type", "pin"}, {"link", "l_foot"}}, 99);
  // an unknown protocol version closes with 1002
  auto other = std::make_unique<WsClient>(server_->ws_port(),
                                          "/ws?session=" + s.id + "&token=" + s.token, origin());
  other->send({{"type", "hello"}, {"protocol", 2}});
  EXPECT_THROW(for (int k = 0; k < 100; ++k) other->read(), std::runtime_error);
  EXPECT_EQ(other->close_code(), 1002);
  // a text frame that is not UTF-8 breaks the WebSocket protocol itself: close 1007 (RFC 6455)
  auto garbled = connect(s);
  garbled->read_until("snapshot");
  garbled->send_text("\xff\xfe garbage");
  EXPECT_THROW(for (int k = 0; k < 100; ++k) garbled->read(), std::runtime_error);
  EXPECT_EQ(garbled->close_code(), 1007);
  auto c = http();
  EXPECT_EQ(c.Get("/api/health")->status, 200);
  EXPECT_EQ(connect(s)->read_until("snapshot").at("session"), s.id);
}

}  // namespace
