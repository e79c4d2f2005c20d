// Tests for server/session_registry.hpp without sockets: a bounded cache of live sessions over
// the saved ones (eviction of the least recently used idle session, reload with its edits, one
// load for concurrent lookups), removal, the list, and a registry without a data folder.
#include "server/session_registry.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>
#include <vector>

#include "io/bundled_characters.hpp"

namespace {

namespace fs = std::filesystem;
using server::SessionRegistry;

std::unique_ptr<animator::Session> new_session() {
  static const auto model = io::load_character("human48").model;
  return std::make_unique<animator::Session>(model, "human48");
}

bool eventually(const std::function<bool()>& done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

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
