// Tests for server/session_registry.hpp without sockets: a bounded cache of live sessions over
// the saved ones (eviction of the least recently used idle session, reload with its edits, one
// load for concurrent lookups), removal, the list, a registry without a data folder, and the
// skinned mesh a session keeps beside its file.
#include "server/session_registry.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <thread>
#include <vector>

#include "io/bundled_characters.hpp"
#include "server/mesh_binary.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;
using server::SessionRegistry;

std::unique_ptr<animator::Session> new_session() {
  static const auto model = io::load_character("human48").model;
  return std::make_unique<animator::Session>(model, "human48");
}

using fixtures::eventually;

class SessionRegistryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pindrag-registry-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::unique_ptr<SessionRegistry> registry(std::size_t max_live, bool on_disk = true) {
    return std::make_unique<SessionRegistry>(server::RegistryOptions{
        .data_dir = on_disk ? dir_.string() : std::string(), .max_live = max_live});
  }
  fs::path dir_;
};

TEST_F(SessionRegistryTest, TheLeastRecentlyUsedIdleSessionLeavesMemoryAndComesBack) {
  auto r = registry(2);
  server::SessionHandle a = r->create(new_session());
  a.actor->call([](animator::Session& s) { s.key_insert(0.25); }, /*edit=*/true);
  server::SessionHandle b = r->create(new_session());
  // both live sessions are held here: no room for a third, and nothing was lost by asking
  EXPECT_THROW(r->create(new_session()), server::SessionsBusy);
  EXPECT_EQ(r->size(), 2u);

  a.actor.reset();  // only the registry holds `a` now
  server::SessionHandle c = r->create(new_session());
  EXPECT_TRUE(eventually([&] { return r->live() <= 2; }));
  EXPECT_EQ(r->size(), 3u);
  for (const server::SessionInfo& info : r->list()) {
    EXPECT_EQ(info.live, info.id != a.id) << info.id;
    EXPECT_EQ(info.character, "human48");
    EXPECT_GT(info.bytes, 0u);
  }

  // back from disk with its key (c, idle now, makes room); the wrong token still gets nothing
  c.actor.reset();
  EXPECT_EQ(r->find(a.id, std::string(32, '0')).status, 401);
  const server::SessionLookup found = r->find(a.id, a.token);
  ASSERT_EQ(found.status, 200);
  EXPECT_EQ(found.actor->call([](animator::Session& s) { return s.keys().keys().size(); }), 1u);
  EXPECT_TRUE(eventually([&] { return r->live() <= 2; }));
}

// a small mesh on human48: a triangle on the pelvis and one shared by the pelvis and a thigh
core::SkinnedMesh small_mesh() {
  core::SkinnedMesh m;
  m.name = "patch";
  m.positions = {{0, 1, 0}, {0.1f, 1, 0}, {0, 1.1f, 0}, {0.1f, 0.8f, 0}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  m.bones = {1, 2};
  m.inverse_bind = {core::Transform::from_translation(core::Vector3(0, -1, 0)),
                    core::Transform::from_translation(core::Vector3(-0.1, -0.9, 0))};
  m.joints = {{0, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 0, 0}, {1, 0, 0, 0}};
  m.weights = {{1, 0, 0, 0}, {0.5f, 0.5f, 0, 0}, {1, 0, 0, 0}, {1, 0, 0, 0}};
  m.base_color = Eigen::Vector4f(0.2f, 0.4f, 0.6f, 1.0f);
  return m;
}

void expect_same_mesh(const core::SkinnedMesh& a, const core::SkinnedMesh& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.normals, b.normals);
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.joints, b.joints);
  EXPECT_EQ(a.weights, b.weights);
  EXPECT_EQ(a.bones, b.bones);
  ASSERT_EQ(a.inverse_bind.size(), b.inverse_bind.size());
  for (std::size_t k = 0; k < a.inverse_bind.size(); ++k) {
    EXPECT_EQ(a.inverse_bind[k].R, b.inverse_bind[k].R);
    EXPECT_EQ(a.inverse_bind[k].p, b.inverse_bind[k].p);
  }
  EXPECT_EQ(a.base_color, b.base_color);
  EXPECT_EQ(a.uvs, b.uvs);
  ASSERT_EQ(a.parts.size(), b.parts.size());
  for (std::size_t k = 0; k < a.parts.size(); ++k) {
    EXPECT_EQ(a.parts[k].first_triangle, b.parts[k].first_triangle);
    EXPECT_EQ(a.parts[k].triangle_count, b.parts[k].triangle_count);
    EXPECT_EQ(a.parts[k].base_color, b.parts[k].base_color);
    EXPECT_EQ(a.parts[k].texture, b.parts[k].texture);
  }
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (std::size_t k = 0; k < a.textures.size(); ++k) {
    EXPECT_EQ(a.textures[k].mime_type, b.textures[k].mime_type);
    EXPECT_EQ(a.textures[k].bytes, b.textures[k].bytes);
  }
}

// small_mesh in two parts, the second painted with a (tiny, not decodable) PNG
core::SkinnedMesh textured_mesh() {
  core::SkinnedMesh m = small_mesh();
  m.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  m.textures.push_back({"image/png", std::string("\x89PNG\r\n\x1a\n", 8) + "rest"});
  m.parts = {{0, 1, Eigen::Vector4f(0.2f, 0.4f, 0.6f, 1.0f), -1},
             {1, 1, Eigen::Vector4f(1.0f, 1.0f, 1.0f, 0.5f), 0}};
  return m;
}

TEST_F(SessionRegistryTest, ASkinnedSessionComesBackWithItsMeshAndABrokenMeshFileLosesOnlyIt) {
  const core::SkinnedMesh mesh = small_mesh();
  std::string id, token, other_id, other_token;
  {
    auto r = registry(4);
    auto session = new_session();
    session->set_skin(std::make_shared<const core::SkinnedMesh>(mesh));
    const server::SessionHandle a = r->create(std::move(session));
    const server::SessionHandle b = r->create([&] {
      auto s = new_session();
      s->set_skin(std::make_shared<const core::SkinnedMesh>(mesh));
      return s;
    }());
    id = a.id, token = a.token, other_id = b.id, other_token = b.token;
    a.actor->call([](animator::Session& s) { s.key_insert(0.5); }, /*edit=*/true);
  }
  ASSERT_TRUE(fs::exists(dir_ / "sessions" / (id + ".mesh")));
  // the other session's mesh file is cut short
  const fs::path broken = dir_ / "sessions" / (other_id + ".mesh");
  fs::resize_file(broken, fs::file_size(broken) - 9);

  auto r = registry(4);
  std::ostringstream log;
  ASSERT_EQ(r->restore(log), 2) << log.str();
  server::SessionLookup found = r->find(id, token);
  ASSERT_EQ(found.status, 200);
  const core::SkinnedMesh back = found.actor->call(
      [](animator::Session& s) { return s.skin() ? *s.skin() : core::SkinnedMesh{}; });
  expect_same_mesh(back, mesh);
  EXPECT_EQ(found.actor->call([](animator::Session& s) { return s.keys().keys().size(); }), 1u);
  const server::SessionLookup other = r->find(other_id, other_token);
  ASSERT_EQ(other.status, 200);
  EXPECT_FALSE(other.actor->call([](animator::Session& s) { return s.skin() != nullptr; }));
  // deleting a session deletes its mesh
  ASSERT_EQ(r->remove(id, token), 409);  // `found` holds it
  found.actor.reset();
  ASSERT_EQ(r->remove(id, token), 200);
  EXPECT_FALSE(fs::exists(dir_ / "sessions" / (id + ".mesh")));
}

TEST(MeshBinary, TexturesPartsAndUvsRoundTripAndAreChecked) {
  const core::SkinnedMesh mesh = textured_mesh();
  ASSERT_EQ(core::check_mesh_materials(mesh), "");
  const std::string bytes = server::encode_mesh_binary(mesh);
  expect_same_mesh(server::decode_mesh_binary(bytes, 5, "m.mesh"), mesh);
  // a mesh written before parts existed still reads: one part of its base colour
  expect_same_mesh(server::decode_mesh_binary(server::encode_mesh_binary(small_mesh()), 5, "m"),
                   small_mesh());

  const auto broken = [](auto change) {
    core::SkinnedMesh m = textured_mesh();
    change(m);
    return m;
  };
  const auto rule_of = [](const core::SkinnedMesh& m) { return core::check_mesh_materials(m); };
  EXPECT_NE(rule_of(broken([](auto& m) { m.uvs.pop_back(); })).find("3 texture coordinates"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) { m.textures[0].bytes = "GIF89a"; })).find("texture 0"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) {
              m.textures[0].mime_type = "image/jpeg";
            })).find("declared 'image/jpeg' but holds image/png"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) { m.parts[1].first_triangle = 0; })).find("part 1"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) { m.parts.pop_back(); })).find("cover 1 of 2"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) { m.parts[1].texture = 1; })).find("texture 1 does not"),
            std::string::npos);
  EXPECT_NE(rule_of(broken([](auto& m) { m.parts[0].base_color[0] = 2; })).find("base colour"),
            std::string::npos);

  // the file's bytes are checked the same way, naming the file
  const auto refused = [&](const std::string& b, const std::string& fragment) {
    try {
      server::decode_mesh_binary(b, 5, "m.mesh");
      ADD_FAILURE() << "accepted; expected " << fragment;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("m.mesh: " + fragment), std::string::npos) << e.what();
    }
  };
  refused(bytes.substr(0, bytes.size() - 4), "textures");
  refused(server::encode_mesh_binary(broken([](auto& m) { m.textures[0].bytes[1] = 'X'; })),
          "texture 0");
  refused(server::encode_mesh_binary(broken([](auto& m) { m.parts[1].texture = 3; })), "part 1");
}

TEST(MeshBinary, RoundTripsAndRefusesWhatDoesNotFitNamingTheField) {
  const core::SkinnedMesh mesh = small_mesh();
  const std::string bytes = server::encode_mesh_binary(mesh);
  expect_same_mesh(server::decode_mesh_binary(bytes, 5, "m.mesh"), mesh);
  const auto refused = [&](const std::string& b, int nlinks, const std::string& fragment) {
    try {
      server::decode_mesh_binary(b, nlinks, "m.mesh");
      ADD_FAILURE() << "accepted; expected " << fragment;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("m.mesh: " + fragment), std::string::npos) << e.what();
    }
  };
  refused(bytes.substr(0, bytes.size() - 8), 5, "weights");
  refused("PDMX" + bytes.substr(4), 5, "not a pindrag mesh");
  refused(bytes.substr(0, 10), 5, "header");
  refused(bytes, 2, "bones");  // bone 2 is beyond a character of one link
  std::string nan_position = bytes;
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 4, 4);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_position.data() + 8 + length, &nan, 4);
  refused(nan_position, 5, "positions");
}

TEST_F(SessionRegistryTest, ConcurrentLookupsOfAStoredSessionLoadItOnce) {
  std::string id, token;
  {
    auto r = registry(4);
    const auto h = r->create(new_session());
    id = h.id;
    token = h.token;
  }
  auto r = registry(4);
  std::ostringstream log;
  EXPECT_EQ(r->restore(log), 1) << log.str();
  EXPECT_EQ(r->live(), 0u);
  std::vector<std::shared_ptr<server::SessionActor>> actors(8);
  std::vector<std::thread> threads;
  for (int i = 0; i < 8; ++i)
    threads.emplace_back([&, i] { actors[i] = r->find(id, token).actor; });
  for (auto& t : threads) t.join();
  for (const auto& a : actors) EXPECT_EQ(a, actors[0]);
  EXPECT_NE(actors[0], nullptr);
  EXPECT_EQ(r->live(), 1u);
}

TEST_F(SessionRegistryTest, RemoveNeedsTheTokenRefusesASessionInUseAndDeletesItsFiles) {
  auto r = registry(4);
  server::SessionHandle h = r->create(new_session());
  const std::string id = h.id, token = h.token;
  EXPECT_EQ(r->remove(id, std::string(32, 'f')), 401);
  EXPECT_EQ(r->remove(std::string(32, 'e'), token), 404);
  EXPECT_EQ(r->remove(id, token), 409);  // `h` holds it
  h.actor.reset();
  // a file the actor may keep beside its session goes too
  std::ofstream(dir_ / "sessions" / (id + ".journal")) << "x";
  EXPECT_EQ(r->remove(id, token), 200);
  for (const auto& e : fs::directory_iterator(dir_ / "sessions"))
    EXPECT_NE(e.path().filename().string().rfind(id, 0), 0u) << e.path();
  EXPECT_EQ(r->find(id, token).status, 404);
  EXPECT_EQ(r->size(), 0u);
}

TEST_F(SessionRegistryTest, WithoutADataFolderNothingLeavesMemoryAndAFullRegistryRefuses) {
  auto r = registry(2, /*on_disk=*/false);
  server::SessionHandle a = r->create(new_session());
  a.actor.reset();
  r->create(new_session());
  // a and b idle, but they have nowhere to go: a third is refused, naming the rule
  try {
    r->create(new_session());
    ADD_FAILURE() << "a third session was created";
  } catch (const server::SessionsBusy& e) {
    EXPECT_NE(std::string(e.what()).find("--data-dir"), std::string::npos) << e.what();
  }
  EXPECT_EQ(r->size(), 2u);
  EXPECT_EQ(r->find(a.id, a.token).status, 200);
  EXPECT_EQ(r->remove(a.id, a.token), 200);
  EXPECT_NO_THROW(r->create(new_session()));
}

int process_threads() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return -1;
}

TEST_F(SessionRegistryTest, FiftyLiveSessionsRunOnTheSameFewThreads) {
  auto r = std::make_unique<SessionRegistry>(
      server::RegistryOptions{.data_dir = "", .max_live = 64, .actor_threads = 2});
  EXPECT_EQ(r->actor_threads(), 2u);
  const int before = process_threads();
  ASSERT_GT(before, 0);
  std::vector<server::SessionHandle> sessions;
  for (int i = 0; i < 50; ++i) sessions.push_back(r->create(new_session()));
  // every session has run work of its own, so each actor has been scheduled
  for (auto& s : sessions) {
    EXPECT_EQ(s.actor->call([](animator::Session& session) { return session.model().nq; }),
              sessions.front().actor->model().nq);
  }
  EXPECT_EQ(r->live(), 50u);
  EXPECT_EQ(process_threads(), before);  // no thread per session
}

}  // namespace
