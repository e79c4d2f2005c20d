// Durability of `pindrag serve`, run as the real executable on a data folder (docs/protocol.md
// "Durability"): killed with SIGKILL right after acknowledgements of random edits, restarted on
// the same folder, it has every acknowledged edit; with the file size limit at zero (SIGXFSZ
// ignored, so writes fail with EFBIG, as on a full disk) every edit gets an error instead of an
// ack, the session stays as it was, HTTP edits answer 507 and the server keeps running.
// $PINDRAG_SERVE_EXE runs another build of pindrag instead of this one.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <thread>

#include "tests/server/ws_test_client.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using server_test::WsClient;

std::string exe() {
  const char* other = std::getenv("PINDRAG_SERVE_EXE");
  return other && *other ? other : PINDRAG_EXE;
}

// `pindrag serve` on `data_dir` as a child process, its ports read from what it prints.
class ServerProcess {
 public:
  explicit ServerProcess(const std::string& data_dir, rlim_t file_size_limit = RLIM_INFINITY) {
    int out[2];
    if (::pipe(out) != 0) throw std::runtime_error("pipe");
    pid_ = ::fork();
    if (pid_ == 0) {
      ::dup2(out[1], 1);
      ::close(out[0]);
      ::close(out[1]);
      if (file_size_limit != RLIM_INFINITY) {
        ::signal(SIGXFSZ, SIG_IGN);  // kept across exec: a write past the limit fails (EFBIG)
        rlimit limit{file_size_limit, file_size_limit};
        ::setrlimit(RLIMIT_FSIZE, &limit);
      }
      const std::string bin = exe();
      ::execl(bin.c_str(), "pindrag", "serve", "--port", "0", "--ws-port", "0", "--data-dir",
              data_dir.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    ::close(out[1]);
    out_ = out[0];
    read_ports();
  }
  ~ServerProcess() {
    kill9();
    if (out_ >= 0) ::close(out_);
  }
  void kill9() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  bool alive() const { return pid_ > 0 && ::waitpid(pid_, nullptr, WNOHANG) == 0; }

  int http_port = 0, ws_port = 0;
  std::string origin() const { return "http://127.0.0.1:" + std::to_string(http_port); }
  httplib::Client http() const {
    httplib::Client c("127.0.0.1", http_port);
    c.set_read_timeout(30, 0);
    return c;
  }

 private:
  // "... WebSocket on port W" and "Open http://127.0.0.1:P/..."
  void read_ports() {
    std::string text;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    const std::regex ports(R"(WebSocket on port (\d+)[\s\S]*Open http://[^:]+:(\d+)/)");
    std::smatch m;
    while (!std::regex_search(text, m, ports)) {
      if (std::chrono::steady_clock::now() > deadline)
        throw std::runtime_error("pindrag serve did not start: " + text);
      pollfd p{out_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buffer[512];
      const ssize_t n = ::read(out_, buffer, sizeof buffer);
      if (n <= 0) throw std::runtime_error("pindrag serve exited: " + text);
      text.append(buffer, static_cast<std::size_t>(n));
    }
    ws_port = std::stoi(m[1]);
    http_port = std::stoi(m[2]);
  }

  pid_t pid_ = -1;
  int out_ = -1;
};

struct Session {
  std::string id, token;
};

Session create_session(const ServerProcess& srv) {
  auto c = srv.http();
  const auto res = c.Post("/api/sessions", {{"Origin", srv.origin()}},
                          json{{"character", "human48"}}.dump(), "application/json");
  if (!res || res->status != 201) throw std::runtime_error("no session: " + (res ? res->body : ""));
  const json j = json::parse(res->body);
  return {j.at("id"), j.at("token")};
}

// A three-joint skeleton with `frames` frames of motion.
std::string small_bvh(int frames) {
  std::string out =
      "HIERARCHY\nROOT hips\n{\n  OFFSET 0 0 0\n"
      "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
      "  JOINT spine\n  {\n    OFFSET 0 10 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "    JOINT head\n    {\n      OFFSET 0 10 0\n      CHANNELS 3 Zrotation Xrotation "
      "Yrotation\n      End Site\n      {\n        OFFSET 0 5 0\n      }\n    }\n  }\n}\n"
      "MOTION\nFrames: " +
      std::to_string(frames) + "\nFrame Time: 0.0333333\n";
  for (int f = 0; f < frames; ++f) {
    const double a = 0.37 * f;
    out += std::to_string(f * 0.1) + " 90 0 " + std::to_string(10 * std::sin(a)) + " " +
           std::to_string(5 * std::cos(a)) + " 1.5 " + std::to_string(20 * std::sin(0.5 * a)) +
           " 3.25 -7.5 " + std::to_string(15 * std::cos(a)) + " 2 4\n";
  }
  return out;
}

Session create_session_from(const ServerProcess& srv, const std::string& bvh) {
  auto c = srv.http();
  const httplib::MultipartFormDataItems items = {{"character", bvh, "walk.bvh", "text/plain"}};
  const auto res = c.Post("/api/sessions", {{"Origin", srv.origin()}}, items);
  if (!res || res->status != 201) throw std::runtime_error("no session: " + (res ? res->body : ""));
  const json j = json::parse(res->body);
  return {j.at("id"), j.at("token")};
}

json snapshot(const ServerProcess& srv, const Session& s) {
  auto c = srv.http();
  const auto res = c.Get("/api/sessions/" + s.id, {{"X-Session-Token", s.token}});
  if (!res || res->status != 200) throw std::runtime_error("no snapshot");
  return json::parse(res->body);
}

std::unique_ptr<WsClient> connect(const ServerProcess& srv, const Session& s) {
  auto ws = std::make_unique<WsClient>(srv.ws_port, "/ws?session=" + s.id + "&token=" + s.token,
                                       srv.origin());
  ws->send({{"type", "hello"}, {"protocol", 1}});
  return ws;
}

// Sends `message` with `id` and returns the `ack` or `error` that answers it.
json request(WsClient& ws, json message, int id) {
  message["id"] = id;
  ws.send(message);
  for (;;) {
    const server_test::WsMessage m = ws.read(std::chrono::seconds(30));
    if (!m.text) continue;
    const json j = m.json();
    const std::string type = j.value("type", "");
    if ((type == "ack" || type == "error") && j.value("id", -1) == id) return j;
  }
}

// What the acknowledged edits made of the session, by the rules of docs/protocol.md.
struct Expected {
  std::map<std::string, std::string> pin_modes;
  std::map<std::string, json> pin_targets;  // set by move_pin
  std::vector<std::pair<double, std::string>> keys;
  double damping = 0, falloff = 0, speed = 1, time = 0, duration = 0, frame_time = 0;
  bool gravity = false;
  json loop;

  static Expected from(const json& snap) {
    Expected e;
    for (const json& p : snap.at("pins")) e.pin_modes[p.at("link")] = p.at("mode");
    for (const json& k : snap.at("keys")) e.keys.emplace_back(k.at("time"), k.at("interpolation"));
    e.damping = snap.at("settings").at("damping");
    e.gravity = snap.at("scene").at("gravity");
    e.falloff = snap.at("falloff");
    const json& pb = snap.at("playback");
    e.speed = pb.at("speed");
    e.time = pb.at("time");
    e.duration = pb.at("duration");
    if (snap.at("clip").is_object()) e.frame_time = snap.at("clip").at("frame_time");
    e.loop = {pb.at("loop"), pb.at("loop_start"), pb.at("loop_end")};
    return e;
  }
  // a drag over the paused clip (no physics) edits the frame shown: the playhead goes to that
  // frame, and the pins hold where their links are there (targets the test does not predict)
  void drag_over_clip() {
    if (gravity || frame_time <= 0) return;
    time = static_cast<double>(std::lround(time / frame_time)) * frame_time;
    pin_targets.clear();
  }
  void insert_key(double t, const std::string& interpolation) {
    for (auto& k : keys) {
      if (std::abs(k.first - t) <= 1e-9) {
        k = {t, interpolation};
        return;
      }
    }
    keys.emplace_back(t, interpolation);
    std::sort(keys.begin(), keys.end());
  }
  // what `snap` misses or has wrong; "" when none
  std::string mismatch(const json& snap) const {
    const Expected got = from(snap);
    std::map<std::string, json> targets;
    for (const json& p : snap.at("pins")) targets[p.at("link")] = p.at("target");
    for (const auto& [link, target] : pin_targets) {
      if (!targets.count(link) || targets[link] != target) return "pin target of " + link;
    }
    if (got.pin_modes != pin_modes) return "pins";
    if (got.keys != keys) return "keys";
    if (got.damping != damping) return "settings.damping";
    if (got.gravity != gravity) return "scene.gravity";
    if (got.falloff != falloff) return "falloff";
    if (got.speed != speed) return "playback.speed";
    if (got.time != time) return "playback.time";
    if (got.loop != loop) return "playback.loop";
    return "";
  }
};

// An edit to send and what it does to the expected state once acknowledged.
struct Edit {
  json message;
  std::function<void(Expected&)> effect;
};

// Random edits; a drag gesture counts as one (its drag_end is what gets acknowledged).
class Edits {
 public:
  explicit Edits(unsigned seed) : rng_(seed) {}

  // sends one edit over `ws` and returns its answer; applies it to `e` when acknowledged
  json run(WsClient& ws, Expected& e, int id) {
    const int kind = pick(0, 12);
    if (kind == 12) {
      // a gesture: the hand dragged 10 cm in five samples
      const json begin = {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", {0.3, 1, 0}}};
      if (request(ws, begin, -id).value("type", "") != "ack") return begin;
      for (int k = 1; k <= 5; ++k) {
        ws.send({{"type", "drag_move"}, {"seq", ++seq_}, {"target", {0.3, 1 + 0.02 * k, 0}}});
      }
      const json answer = request(ws, {{"type", "drag_end"}}, id);
      if (answer.value("type", "") == "ack") e.drag_over_clip();
      return answer;
    }
    const Edit edit = kind < 4 ? pin_edit(e) : kind < 8 ? key_edit(e) : setting_edit();
    const json answer = request(ws, edit.message, id);
    if (answer.value("type", "") == "ack") edit.effect(e);
    return answer;
  }

 private:
  Edit pin_edit(const Expected& e) {
    static const char* kLinks[] = {"l_foot", "r_foot", "l_hand", "head", "pelvis", "l_farm"};
    std::vector<std::string> pinned;
    for (const auto& p : e.pin_modes) pinned.push_back(p.first);
    const int kind = pinned.empty() ? 0 : pick(0, 3);
    if (kind <= 1) {
      const std::string link = kLinks[pick(0, 5)], mode = pick(0, 1) ? "position" : "pose";
      return {{{"type", "pin"}, {"link", link}, {"mode", mode}}, [link, mode](Expected& x) {
                x.pin_modes[link] = mode;
                x.pin_targets.erase(link);
              }};
    }
    const std::string link = pinned[pick(0, static_cast<int>(pinned.size()) - 1)];
    if (kind == 2) {
      return {{{"type", "unpin"}, {"link", link}}, [link](Expected& x) {
                x.pin_modes.erase(link);
                x.pin_targets.erase(link);
              }};
    }
    const json target = {real(-0.5, 0.5), real(0, 1.5), real(-0.5, 0.5)};
    return {{{"type", "move_pin"}, {"link", link}, {"target", target}},
            [link, target](Expected& x) { x.pin_targets[link] = target; }};
  }

  Edit key_edit(const Expected& e) {
    const int n = static_cast<int>(e.keys.size());
    const int kind = n == 0 ? 0 : pick(0, 3);
    if (kind <= 1) {
      const double t = pick(0, 400) * 0.25;
      const std::string interpolation = pick(0, 1) ? "smooth" : "linear";
      return {{{"type", "key_insert"}, {"time", t}, {"interpolation", interpolation}},
              [t, interpolation](Expected& x) { x.insert_key(t, interpolation); }};
    }
    const int i = pick(0, n - 1);
    if (kind == 2) {
      return {{{"type", "key_delete"}, {"index", i}},
              [i](Expected& x) { x.keys.erase(x.keys.begin() + i); }};
    }
    const double t = pick(0, 400) * 0.25 + 0.125;
    return {{{"type", "key_move"}, {"index", i}, {"time", t}}, [i, t](Expected& x) {
              const std::string interpolation = x.keys[i].second;
              x.keys.erase(x.keys.begin() + i);
              x.insert_key(t, interpolation);
            }};
  }

  Edit setting_edit() {
    switch (pick(0, 5)) {
      case 0: {
        const double d = real(0.01, 0.1);
        return {{{"type", "set_settings"}, {"settings", {{"damping", d}}}},
                [d](Expected& x) { x.damping = d; }};
      }
      case 1: {
        const bool g = pick(0, 1) == 1;
        return {{{"type", "set_effects"}, {"scene", {{"gravity", g}}}},
                [g](Expected& x) { x.gravity = g; }};
      }
      case 2: {
        const double f = real(0, 2);
        return {{{"type", "set_falloff"}, {"seconds", f}}, [f](Expected& x) { x.falloff = f; }};
      }
      case 3: {
        const double v = real(-2, 2);
        return {{{"type", "set_speed"}, {"speed", v}}, [v](Expected& x) { x.speed = v; }};
      }
      case 4: {
        const double t = real(0, 100);
        return {{{"type", "seek"}, {"time", t}},
                [t](Expected& x) { x.time = std::min(t, x.duration); }};
      }
      default: {
        const double start = real(0, 10), end = start + real(0, 10);
        return {{{"type", "set_loop"}, {"loop", true}, {"start", start}, {"end", end}},
                [start, end](Expected& x) {
                  x.loop = {true, start, end};
                }};
      }
    }
  }

  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double real(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng_); }
  std::mt19937 rng_;
  std::uint32_t seq_ = 0;
};

class DurabilityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("pindrag-durability-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_);
    data_ = (base_ / "data").string();
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(base_, ec);
  }
  fs::path base_;
  std::string data_;
};

TEST_F(DurabilityTest, EveryAcknowledgedEditSurvivesKillNine) {
  constexpr int kEdits = 200;
  constexpr int kKills = 25;
  auto srv = std::make_unique<ServerProcess>(data_);
  const Session s = create_session(*srv);
  auto ws = connect(*srv, s);
  // a clip of two minutes: a save of the whole session takes a while, as in real use
  ASSERT_EQ(request(*ws, {{"type", "key_insert"}, {"time", 0}}, 1).at("type"), "ack");
  ASSERT_EQ(request(*ws, {{"type", "key_insert"}, {"time", 120}}, 2).at("type"), "ack");
  ASSERT_EQ(request(*ws, {{"type", "bake_keys"}, {"rate", 30}}, 3).at("type"), "ack");
  Expected expected = Expected::from(snapshot(*srv, s));
  ASSERT_EQ(expected.duration, 120);

  std::mt19937 rng(2024);
  std::set<int> kill_after;
  while (static_cast<int>(kill_after.size()) < kKills) {
    kill_after.insert(std::uniform_int_distribution<int>(0, kEdits - 1)(rng));
  }
  Edits edits(7);
  int kills = 0;
  for (int k = 0; k < kEdits; ++k) {
    const json answer = edits.run(*ws, expected, 100 + k);
    ASSERT_EQ(answer.value("type", ""), "ack") << answer;
    if (!kill_after.count(k)) continue;
    // right after the ack: nothing more is read or sent
    srv->kill9();
    ws.reset();
    ++kills;
    srv = std::make_unique<ServerProcess>(data_);
    const json restored = snapshot(*srv, s);
    ASSERT_EQ(expected.mismatch(restored), "") << "after edit " << k << " (kill " << kills << ")";
    ws = connect(*srv, s);
  }
  EXPECT_EQ(kills, kKills);
  // the files are the owner's only
  for (const auto& entry : fs::directory_iterator(fs::path(data_) / "sessions")) {
    if (entry.path().extension() == ".tmp") continue;
    struct stat st {};
    ASSERT_EQ(::stat(entry.path().c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0600u) << entry.path();
  }
}

TEST_F(DurabilityTest, AFullDiskGivesAnErrorPerEditAndLosesNothing) {
  const std::string bvh = small_bvh(200);
  auto srv = std::make_unique<ServerProcess>(data_);
  const Session s = create_session(*srv);
  const Session walk = create_session_from(*srv, bvh);  // a session the BVH's clip fits
  {
    auto ws = connect(*srv, s);
    ASSERT_EQ(request(*ws, {{"type", "pin"}, {"link", "l_foot"}}, 1).at("type"), "ack");
    ASSERT_EQ(request(*ws, {{"type", "key_insert"}, {"time", 0}}, 2).at("type"), "ack");
    ASSERT_EQ(request(*ws, {{"type", "key_insert"}, {"time", 2}}, 3).at("type"), "ack");
  }
  srv->kill9();

  // no file may grow: every write fails with EFBIG
  srv = std::make_unique<ServerProcess>(data_, /*file_size_limit=*/0);
  const json before = snapshot(*srv, s);
  const json walk_before = snapshot(*srv, walk);
  auto ws = connect(*srv, s);
  const std::vector<json> edits = {
      {{"type", "pin"}, {"link", "r_hand"}},
      {{"type", "unpin"}, {"link", "l_foot"}},
      {{"type", "key_insert"}, {"time", 1}},
      {{"type", "key_delete"}, {"index", 0}},
      {{"type", "set_falloff"}, {"seconds", 1.25}},
      {{"type", "set_settings"}, {"settings", {{"damping", 0.07}}}},
      {{"type", "seek"}, {"time", 1}},
      {{"type", "bake_keys"}},
      {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", {0.3, 1, 0}}},
      {{"type", "drag_move"}, {"seq", 1}, {"target", {0.3, 1.1, 0}}},
      {{"type", "drag_end"}},
  };
  int id = 10;
  for (const json& m : edits) {
    const json answer = request(*ws, m, ++id);
    const std::string type = m.at("type");
    if (type == "drag_begin" || type == "drag_move") {
      // nothing saved changes until the gesture ends
      EXPECT_EQ(answer.at("type"), "ack") << m;
      continue;
    }
    ASSERT_EQ(answer.at("type"), "error") << m << " -> " << answer;
    EXPECT_EQ(answer.at("message"), type + ": not saved (File too large), so not applied");
    EXPECT_EQ(answer.value("code", ""), "not_saved");
    EXPECT_EQ(snapshot(*srv, s), before) << "after " << m;
  }
  // HTTP edits answer 507
  const httplib::MultipartFormDataItems clip = {{"clip", bvh, "walk.bvh", "text/plain"}};
  auto upload = [&] {
    auto h = srv->http();
    return h.Post("/api/sessions/" + walk.id + "/clip",
                  {{"X-Session-Token", walk.token}, {"Origin", srv->origin()}}, clip);
  };
  auto res = upload();
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 507) << res->body;
  auto h = srv->http();
  res = h.Post("/api/sessions", {{"Origin", srv->origin()}}, json{{"character", "human48"}}.dump(),
               "application/json");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 507) << res->body;
  res = h.Get("/api/health");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_TRUE(srv->alive());

  // room for the uploaded file but not for the clip's journal record: the edit is refused there
  srv->kill9();
  srv = std::make_unique<ServerProcess>(data_, bvh.size() + 16384);
  res = upload();
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 507) << res->body;
  EXPECT_NE(res->body.find("not saved (File too large), so not applied"), std::string::npos)
      << res->body;
  EXPECT_EQ(snapshot(*srv, walk), walk_before);

  // with room again, both sessions are what they were before the disk filled
  srv->kill9();
  srv = std::make_unique<ServerProcess>(data_);
  for (const auto& [session, was] : {std::pair{s, before}, std::pair{walk, walk_before}}) {
    const json after = snapshot(*srv, session);
    for (const char* part : {"pins", "keys", "clip", "layers", "settings", "falloff"}) {
      EXPECT_EQ(after.at(part), was.at(part)) << part;
    }
  }
}

}  // namespace
