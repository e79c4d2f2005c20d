// The budgets of docs/protocol.md ("Limits") over real sockets: uploads over their type's cap get
// 413 naming it, files whose motion is over the clip budget get 422 naming the limit, edits over
// a limit get an error naming it, and a thumbnail or export of a few frames of a very long
// animation samples only those frames.
// the project's headers (Eigen) before httplib.h: glibc's <resolv.h>, which it includes,
// defines a macro `_res` that breaks Eigen's headers when they come later
#include "server/server.hpp"

#include <gtest/gtest.h>
#include <httplib.h>
#include <sys/resource.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "animator/session_file.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "io/gltf.hpp"
#include "tests/io/gltf_reader.hpp"
#include "tests/io/stick_figure_document.hpp"
#include "tests/server/ws_test_client.hpp"

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// A BVH of two joints (6 values a frame) and `frames` frames at 100 fps.
std::string bvh_text(int frames) {
  std::string text =
      "HIERARCHY\nROOT hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
      "JOINT chest\n{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n"
      "End Site\n{\nOFFSET 0 10 0\n}\n}\n}\nMOTION\nFrames: " +
      std::to_string(frames) + "\nFrame Time: 0.01\n";
  for (int f = 0; f < frames; ++f) text += "0 1 2 3 4 5\n";
  return text;
}

long peak_rss_kib() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

class LimitsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    base_ = fs::temp_directory_path() /
            ("pindrag-limits-test-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(base_);
    fs::create_directories(base_ / "web");
    std::ofstream(base_ / "web" / "index.html") << "<!doctype html><title>pindrag</title>";
    options_.port = 0;
    options_.ws_port = 0;
    options_.data_dir = (base_ / "data").string();
    options_.web_root = (base_ / "web").string();
  }
  void TearDown() override {
    server_.reset();
    std::error_code ec;
    fs::remove_all(base_, ec);
  }
  void start() {
    server_ = std::make_unique<server::Server>(options_);
    server_->start();
  }

  std::string origin() const { return "http://127.0.0.1:" + std::to_string(server_->http_port()); }
  httplib::Client http() const {
    httplib::Client c("127.0.0.1", server_->http_port());
    c.set_read_timeout(60, 0);
    return c;
  }
  // POST /api/sessions with a file; the reply
  httplib::Result upload_character(const std::string& name, const std::string& bytes) {
    httplib::MultipartFormDataItems items{{"character", bytes, name, "application/octet-stream"}};
    return http().Post("/api/sessions", {{"Origin", origin()}}, items);
  }
  struct Created {
    std::string id, token;
  };
  Created create_session() {
    const auto res = http().Post("/api/sessions", {{"Origin", origin()}},
                                 json{{"character", "human48"}}.dump(), "application/json");
    EXPECT_TRUE(res && res->status == 201);
    const json j = json::parse(res->body);
    return {j.at("id"), j.at("token")};
  }
  static std::string error_of(const httplib::Result& res) {
    return res ? json::parse(res->body).value("error", "") : "no reply";
  }

  fs::path base_;
  server::ServerOptions options_;
  std::unique_ptr<server::Server> server_;
};

TEST_F(LimitsTest, TheConfigReportsEveryBudget) {
  start();
  const json limits = json::parse(http().Get("/api/config")->body).at("limits");
  EXPECT_EQ(limits.at("upload_bytes"), 64 << 20);
  EXPECT_EQ(limits.at("upload_bytes_by_type").at("urdf"), 4 << 20);
  EXPECT_EQ(limits.at("upload_bytes_by_type").at("bvh"), 64 << 20);
  EXPECT_EQ(limits.at("clip_seconds"), 3600.0);
  EXPECT_EQ(limits.at("clip_frames"), 216000);
  EXPECT_EQ(limits.at("keys"), 10000);
  EXPECT_EQ(limits.at("layers"), 64);
  EXPECT_EQ(limits.at("undo_bytes"), 64 << 20);
}

TEST_F(LimitsTest, UploadsOverTheirTypesCapGet413NamingIt) {
  options_.uploads.bvh = 4096;
  start();
  // a 5 MiB character JSON: over the 4 MiB default for .json, under the largest cap
  auto res = upload_character("big.json", std::string(5 << 20, ' '));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 413);
  EXPECT_NE(error_of(res).find("character: \"big.json\" is 5 MiB, over the upload cap of 4 MiB "
                               "for .json files (set by pindrag serve --max-upload-json)"),
            std::string::npos)
      << error_of(res);
  // a BVH over the cap this server was given
  res = upload_character("walk.bvh", bvh_text(400));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 413);
  EXPECT_NE(error_of(res).find("(set by pindrag serve --max-upload-bvh)"), std::string::npos)
      << error_of(res);
  // the same as a clip of a session
  const Created s = create_session();
  httplib::MultipartFormDataItems clip{{"clip", bvh_text(400), "walk.bvh", "text/plain"}};
  res = http().Post("/api/sessions/" + s.id + "/clip",
                    {{"X-Session-Token", s.token}, {"Origin", origin()}}, clip);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 413);
  EXPECT_NE(error_of(res).find("clip: \"walk.bvh\""), std::string::npos) << error_of(res);
  // under the cap: created
  res = upload_character("walk.bvh", bvh_text(20));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 201) << res->body;
  EXPECT_EQ(http().Get("/api/health")->status, 200);
}

TEST_F(LimitsTest, MotionOverTheClipBudgetIsRefusedNamingTheLimit) {
  options_.limits.max_clip_frames = 100;
  start();
  auto res = upload_character("long.bvh", bvh_text(200));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 422);
  EXPECT_NE(error_of(res).find("200 frames exceed the limit of 100 frames per clip (set by "
                               "pindrag serve --max-clip-frames)"),
            std::string::npos)
      << error_of(res);
  // the glTF: a key at 33,000 s (990,001 frames at 30 fps) in a few kilobytes
  const auto m = core::build_human_figure({});
  core::Clip two_keys;
  two_keys.frame_time = 33'000;
  two_keys.frames = {core::neutral_configuration(*m), core::neutral_configuration(*m)};
  io::GltfExportOptions stick;
  stick.stick_figure = true;
  const std::vector<std::uint8_t> glb = io::write_glb(*m, &two_keys, nullptr, stick);
  res = upload_character("long.glb", std::string(glb.begin(), glb.end()));
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 422);
  EXPECT_NE(error_of(res).find("33000 s exceed the limit of 3600 s per clip (set by pindrag serve "
                               "--max-clip-seconds)"),
            std::string::npos)
      << error_of(res);
  EXPECT_EQ(server_->registry().size(), 0u);
}

// A .gltf whose buffer is a file beside it (as Blender's "glTF Separate" writes it) opens when
// that file is sent with it as a "resource" field, and only then; resource names are plain
// file names in the upload's own folder.
TEST_F(LimitsTest, AGltfOpensWithTheBufferFilesSentBesideIt) {
  start();
  const auto m = core::build_human_figure({});
  core::Clip clip;
  clip.frames = {core::neutral_configuration(*m), core::neutral_configuration(*m)};
  std::vector<std::string> errors;
  gltf_test::Document doc = gltf_test::stick_figure_document(*m, clip, errors);
  ASSERT_TRUE(errors.empty()) << errors.front();
  doc.json["buffers"][0]["uri"] = "figure%20data.bin";  // percent-encoded, as URIs are
  const std::string gltf = doc.json.dump();
  const std::string bin(doc.bin.begin(), doc.bin.end());
  auto upload = [&](const std::string& main_name, const std::string& main,
                    const std::vector<std::pair<std::string, std::string>>& resources) {
    httplib::MultipartFormDataItems items{{"character", main, main_name, "model/gltf+json"}};
    for (const auto& [name, bytes] : resources) {
      items.push_back({"resource", bytes, name, "application/octet-stream"});
    }
    return http().Post("/api/sessions", {{"Origin", origin()}}, items);
  };
  // alone: refused before any import, naming the buffer and what to do
  auto res = upload("figure.gltf", gltf, {});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 422);
  EXPECT_EQ(error_of(res),
            "character: \"figure.gltf\" references the buffer \"figure_data.bin\", which was not "
            "sent with it (rule: a .gltf comes with the files its buffers name, beside it: choose "
            "them together in the page, or upload the .glb)");
  // a resource whose name leaves the folder, or is the stored upload's own name
  for (const std::string bad :
       {"../figure data.bin", "sub/figure data.bin", ".hidden.bin", "upload.gltf"}) {
    res = upload("figure.gltf", gltf, {{bad, bin}, {"figure data.bin", bin}});
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 400) << bad;
    EXPECT_NE(error_of(res).find("is not a plain file name"), std::string::npos) << error_of(res);
  }
  // resources with a file that references none
  res = upload("walk.bvh", bvh_text(20), {{"figure data.bin", bin}});
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 400);
  EXPECT_NE(
      error_of(res).find("only a .gltf, .glb, .fbx or .dae is sent with the files it references"),
      std::string::npos)
      << error_of(res);
  EXPECT_EQ(server_->registry().size(), 0u);
  // with its buffer: created, the figure's skeleton and its two frames
  res = upload("figure.gltf", gltf, {{"figure data.bin", bin}});
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 201) << res->body;
  EXPECT_EQ(server_->registry().size(), 1u);
  // the same for a clip of a session: the mapping editor's guess reads the skeleton
  const Created s = create_session();
  auto correspondence = [&](bool with_buffer) {
    httplib::MultipartFormDataItems items{{"clip", gltf, "figure.gltf", "model/gltf+json"}};
    if (with_buffer) items.push_back({"resource", bin, "figure data.bin", ""});
    return http().Post("/api/sessions/" + s.id + "/clip/correspondence",
                       {{"X-Session-Token", s.token}, {"Origin", origin()}}, items);
  };
  res = correspondence(false);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 422);
  EXPECT_NE(error_of(res).find("clip: \"figure.gltf\" references the buffer \"figure_data.bin\""),
            std::string::npos)
      << error_of(res);
  res = correspondence(true);
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_FALSE(json::parse(res->body).at("joints").empty());
}

TEST_F(LimitsTest, AnEditOverALimitGetsAnErrorNamingIt) {
  options_.limits.max_keys = 2;
  start();
  const Created s = create_session();
  server_test::WsClient ws(server_->ws_port(), "/ws?session=" + s.id + "&token=" + s.token,
                           origin());
  ws.send({{"type", "hello"}, {"protocol", 1}});
  ws.read_until("snapshot");
  auto reply_to = [&ws](const json& message) {
    ws.send(message);
    for (;;) {
      const server_test::WsMessage m = ws.read();
      if (!m.text) continue;
      const json j = m.json();
      if (j.contains("id") && j.at("id") == message.at("id")) return j;
    }
  };
  json r = reply_to({{"type", "key_insert"}, {"time", 1e6}, {"id", 1}});
  EXPECT_EQ(r.at("type"), "error");
  EXPECT_EQ(r.value("message", ""),
            "key_insert.time: 1000000 s is beyond the limit of 3600 s per clip (set by pindrag "
            "serve --max-clip-seconds)");
  EXPECT_EQ(reply_to({{"type", "key_insert"}, {"time", 0}, {"id", 2}}).at("type"), "ack");
  EXPECT_EQ(reply_to({{"type", "key_insert"}, {"time", 1}, {"id", 3}}).at("type"), "ack");
  r = reply_to({{"type", "key_insert"}, {"time", 2}, {"id", 4}});
  EXPECT_EQ(r.at("type"), "error");
  EXPECT_NE(r.value("message", "")
                .find("2 keys, the most it may hold (set by pindrag serve "
                      "--max-keys"),
            std::string::npos)
      << r.dump();
}

// The case: keys at 0 s and at 1,000,000 s (a session saved under other limits), then a
// thumbnail of frame 0. It used to build the whole clip (3×10⁷ frames, 30–46 s, 3.7–5.2 GB);
// now the one frame is sampled from the keys.
TEST_F(LimitsTest, AThumbnailOfOneFrameOfAMillionSecondAnimationSamplesThatFrame) {
  {
    auto session = std::make_unique<animator::Session>(core::build_human_figure({}), "human48");
    animator::Limits wide;
    wide.max_clip_seconds = 2e6;
    session->set_limits(wide);
    session->key_insert(0.0);
    session->set_pose(core::random_configuration(session->model(), 1));
    session->key_insert(1e6);
    const std::string id(32, 'a'), token(32, 'b');
    fs::create_directories(base_ / "data" / "sessions");
    animator::save_session(*session, (base_ / "data" / "sessions" / (id + ".json")).string());
    std::ofstream(base_ / "data" / "sessions" / (id + ".token")) << token;
  }
  start();
  ASSERT_EQ(server_->restored_sessions(), 1);
  const std::string path = "/api/sessions/" + std::string(32, 'a');
  const httplib::Headers token{{"X-Session-Token", std::string(32, 'b')}};
  const long rss_before = peak_rss_kib();
  auto res = http().Get(path + "/thumbnail.png?frame=0&size=32", token);
  ASSERT_TRUE(res);
  if (res->status == 501) GTEST_SKIP() << "built without the thumbnail renderer";
  EXPECT_EQ(res->status, 200) << res->body;
  res = http().Get(path + "/thumbnail.png?frame=30000000&size=32", token);
  EXPECT_EQ(res->status, 200) << res->body;
  res = http().Get(path + "/thumbnail.png?frame=30000001", token);
  EXPECT_EQ(res->status, 400);
  EXPECT_NE(error_of(res).find("30000001 frames"), std::string::npos) << error_of(res);
  // the whole animation is over the clip budget: refused, naming the limit; a range is sampled
  res = http().Get(path + "/export?format=bvh", token);
  EXPECT_EQ(res->status, 422);
  EXPECT_NE(error_of(res).find("--max-clip-seconds"), std::string::npos) << error_of(res);
  res = http().Get(path + "/export?format=bvh&first=15000000&last=15000029", token);
  EXPECT_EQ(res->status, 200) << res->body;
  EXPECT_NE(res->body.find("Frames: 30"), std::string::npos);
  res = http().Get(path + "/export?format=bvh&first=5&last=4", token);
  EXPECT_EQ(res->status, 400);
  // one frame of 3×10⁷ frames × 61 coordinates would be 15 GB built whole
  const long grown_mib = (peak_rss_kib() - rss_before) / 1024;
  std::printf("thumbnail and export of a 30,000,001-frame animation: peak RSS grew %ld MiB\n",
              grown_mib);
  EXPECT_LT(grown_mib, 256);
}

}  // namespace
