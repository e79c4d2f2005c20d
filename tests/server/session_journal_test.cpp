// Tests for server/session_journal.hpp and the actor's use of it: a snapshot with its journal
// replayed is the session bit for bit (after random edits, undo, gestures, motion edits and
// settling, with snapshots in between and a crash between a snapshot and the journal's
// truncation); torn and damaged records; files private to their owner; and an edit that cannot
// be written gets an error, not an ack, and is taken back exactly.
#include "server/session_journal.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "animator/session_file.hpp"
#include "io/bundled_characters.hpp"
#include "io/read_file.hpp"
#include "server/apply_message.hpp"
#include "server/protocol.hpp"
#include "server/session_actor.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using server::SessionJournal;

// A fresh folder per test.
class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("pindrag-journal-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

// Holds the process's file size limit at `bytes` (writes beyond fail with EFBIG, SIGXFSZ
// ignored) until it goes out of scope.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limit = saved_;
    limit.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    ::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit saved_{};
  sighandler_t old_handler_{};
};

std::string document_of(const animator::Session& s) {
  return animator::session_to_json(s, /*include_character=*/false).dump();
}

std::string reload(const std::string& path) {
  std::ostringstream log;
  const SessionJournal::Loaded loaded = SessionJournal::load(path, log);
  EXPECT_EQ(log.str(), "");
  return document_of(*loaded.session);
}

unsigned mode_of(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return 0;
  return st.st_mode & 0777;
}

// Random edits of every kind a client makes, each applied as the server applies messages and
// followed by a few solver ticks (the figure settling, playback running).
class RandomEditor {
 public:
  RandomEditor(animator::Session& s, unsigned seed) : s_(s), rng_(seed) {}

  int motion_edits = 0;  // drags during playback that left an edit layer

  // one edit; returns the message applied (null when it was refused)
  json step() {
    if (s_.clip() && pick(0, 9) == 0) return motion_edit();
    const json m = next();
    try {
      server::apply(s_, server::parse_client_message(m.dump()).message);
    } catch (const std::exception&) {
      return nullptr;  // refused: the session is unchanged
    }
    const int ticks = pick(0, 4);
    for (int k = 0; k < ticks; ++k) s_.tick(1.0 / 60);
    return m;
  }

 private:
  int pick(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  double real(double lo, double hi) { return std::uniform_real_distribution<>(lo, hi)(rng_); }
  std::string link() {
    static const char* kLinks[] = {"l_foot", "r_foot", "l_hand", "r_hand", "head", "pelvis"};
    return kLinks[pick(0, 5)];
  }
  json target() {
    const int i = s_.model().link_index("r_hand");
    const core::Vector3 p = s_.kinematics().X_W[i].p;
    return {p.x() + real(-0.1, 0.1), p.y() + real(-0.1, 0.1), p.z() + real(-0.1, 0.1)};
  }
  // play, drag the hand for a few frames, release: a new edit layer
  json motion_edit() {
    const std::size_t layers = s_.layers().size();
    s_.play();
    server::apply(s_,
                  server::parse_client_message(
                      json{{"type", "drag_begin"}, {"link", "r_hand"}, {"target", target()}}.dump())
                      .message);
    for (int k = 0; k < 8; ++k) {
      s_.drag_move(core::Vector3(target()[0], target()[1], target()[2]));
      s_.tick(1.0 / 30);
    }
    s_.drag_end();
    if (pick(0, 1)) s_.pause();
    if (s_.layers().size() > layers) ++motion_edits;
    return {{"type", "drag_end"}};
  }
  json next() {
    const int layers = static_cast<int>(s_.layers().size());
    if (layers > 0 && pick(0, 5) == 0) {
      switch (pick(0, 3)) {
        case 0:
          return {{"type", "layer"}, {"index", pick(0, layers - 1)}, {"muted", pick(0, 1) == 1}};
        case 1:
          return {{"type", "layer"}, {"index", pick(0, layers - 1)}, {"weight", real(0, 2)}};
        case 2:
          return {{"type", "layer"}, {"index", pick(0, layers - 1)}, {"remove", true}};
        default:
          return {{"type", "bake_layers"}};
      }
    }
    const int keys = static_cast<int>(s_.keys().keys().size());
    switch (pick(0, 17)) {
      case 0:
      case 1:
        return {{"type", "pin"}, {"link", link()}, {"mode", pick(0, 1) ? "position" : "pose"}};
      case 2:
        return {{"type", "unpin"}, {"link", link()}};
      case 3:
        return {{"type", "move_pin"}, {"link", link()}, {"target", target()}};
      case 4:
      case 5:
        return {{"type", "key_insert"}, {"time", pick(0, 40) * 0.25}};
      case 6:
        return {{"type", "key_delete"}, {"index", pick(0, std::max(0, keys - 1))}};
      case 7:
        return {
            {"type", "key_move"}, {"index", pick(0, std::max(0, keys - 1))}, {"time", real(0, 10)}};
      case 8:
        return {{"type", "set_settings"}, {"settings", {{"damping", real(0.01, 0.1)}}}};
      case 9:
        return {{"type", "set_effects"}, {"scene", {{"gravity", pick(0, 1) == 1}}}};
      case 10:
        return {{"type", "seek"}, {"time", real(0, 5)}};
      case 11:
        return {{"type", pick(0, 1) ? "undo" : "redo"}};
      case 12:
        return {{"type", "set_falloff"}, {"seconds", real(0, 2)}};
      case 13:
        return {{"type", "bake_keys"}, {"rate", 10}};
      case 14:
        return {{"type", pick(0, 1) ? "play" : "pause"}};
      case 15:
        return {{"type", "drag_begin"}, {"link", "r_hand"}, {"target", target()}};
      case 16:
        return {{"type", "drag_move"}, {"seq", ++seq_}, {"target", target()}};
      default:
        return {{"type", "drag_end"}};
    }
  }

  animator::Session& s_;
  std::mt19937 rng_;
  std::uint32_t seq_ = 0;
};

TEST(SessionJournal, ReplayReproducesTheSessionBitForBit) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  animator::Session live(fixtures::bundled_human48(), "human48");
  auto journal = SessionJournal::start(path, live);
  RandomEditor editor(live, 11);
  int recorded = 0, snapshots = 0;
  for (int k = 0; k < 300; ++k) {
    const json op = editor.step();
    if (op.is_null()) continue;
    if (journal->record(live, op)) ++recorded;
    if (k % 37 == 36) {
      journal->snapshot_now();
      ++snapshots;
    }
    if (k % 25 == 0) {
      ASSERT_EQ(reload(path), document_of(live)) << "after edit " << k;
    }
  }
  EXPECT_GT(recorded, 150);
  EXPECT_GT(editor.motion_edits, 3);  // edit layers were made, changed, baked and undone
  EXPECT_EQ(reload(path), document_of(live));
  EXPECT_EQ(journal->snapshots(), static_cast<std::uint64_t>(snapshots));
}

TEST(SessionJournal, ACrashBetweenSnapshotAndTruncationReplaysNothingTwice) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  animator::Session live(fixtures::bundled_human48(), "human48");
  auto journal = SessionJournal::start(path, live);
  RandomEditor editor(live, 5);
  for (int k = 0; k < 60; ++k) {
    const json op = editor.step();
    if (!op.is_null()) journal->record(live, op);
  }
  const std::string journal_file = SessionJournal::journal_path(path);
  const std::string records = io::read_file(journal_file, 1 << 26);
  ASSERT_GT(journal->journal_records(), 10u);
  // the snapshot was renamed into place, then the process died before the journal was emptied
  animator::SessionImage image = animator::session_image(live);
  image.journal_seq = journal->seq();
  animator::save_session(image, path);
  EXPECT_EQ(reload(path), document_of(live));
  // the same with a few records after the snapshot: only those replay
  for (int k = 0; k < 20; ++k) {
    const json op = editor.step();
    if (!op.is_null()) journal->record(live, op);
  }
  EXPECT_EQ(reload(path), document_of(live));
  // and replay after a reload is as good as the first
  EXPECT_EQ(reload(path), document_of(live));
}

TEST(SessionJournal, ATornRecordIsDroppedAndADamagedOneIsKeptAside) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  animator::Session live(fixtures::bundled_human48(), "human48");
  auto journal = SessionJournal::start(path, live);
  live.key_insert(0.0);
  journal->record(live, json{{"type", "key_insert"}});
  const std::string after_one = document_of(live);
  live.key_insert(1.0);
  journal->record(live, json{{"type", "key_insert"}});
  journal.reset();
  const std::string journal_file = SessionJournal::journal_path(path);
  const std::string bytes = io::read_file(journal_file, 1 << 26);

  // torn: the second record cut short
  std::ofstream(journal_file, std::ios::binary | std::ios::trunc)
      << bytes.substr(0, bytes.size() - 5);
  std::ostringstream log;
  SessionJournal::Loaded loaded = SessionJournal::load(path, log);
  EXPECT_EQ(document_of(*loaded.session), after_one);
  EXPECT_NE(log.str().find("cut short"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("never acknowledged"), std::string::npos) << log.str();
  loaded.journal.reset();
  EXPECT_LT(fs::file_size(journal_file), bytes.size() - 5);  // the torn bytes are cut off

  // damaged: a flipped bit in the first record's payload stops the replay before it
  std::string damaged = bytes;
  damaged[io::kJournalHeaderBytes + 3] ^= 0x20;
  std::ofstream(journal_file, std::ios::binary | std::ios::trunc) << damaged;
  log.str("");
  loaded = SessionJournal::load(path, log);
  EXPECT_EQ(loaded.session->keys().keys().size(), 0u);
  EXPECT_NE(log.str().find("checksum mismatch"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find(".journal.damaged"), std::string::npos) << log.str();
  EXPECT_EQ(io::read_file(journal_file + ".damaged", 1 << 26), damaged);
}

TEST(SessionJournal, SessionFilesAndJournalsAreOwnerOnly) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  animator::Session live(fixtures::bundled_human48(), "human48");
  auto journal = SessionJournal::start(path, live);
  EXPECT_EQ(mode_of(path), 0600u);
  EXPECT_EQ(mode_of(SessionJournal::journal_path(path)), 0600u);
  live.key_insert(0.0);
  journal->record(live, json{{"type", "key_insert"}});
  journal->snapshot_now();
  EXPECT_EQ(mode_of(path), 0600u);
  EXPECT_EQ(mode_of(SessionJournal::journal_path(path)), 0600u);
  EXPECT_EQ(journal->journal_bytes(), 0u);
  // a session saved before files were private is made so when it loads
  journal.reset();
  ::chmod(path.c_str(), 0644);
  reload(path);
  EXPECT_EQ(mode_of(path), 0600u);
}

TEST(SessionJournal, SnapshotsRunInTheBackgroundAndWaitAfterAFailure) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  animator::Session live(fixtures::bundled_human48(), "human48");
  auto journal = SessionJournal::start(path, live);
  auto edit_many = [&] {
    for (std::size_t k = 0; k < SessionJournal::kSnapshotRecords; ++k) {
      live.key_insert(0.1 * static_cast<double>(live.keys().keys().size()));
      ASSERT_TRUE(journal->record(live, json{{"type", "key_insert"}}));
    }
  };
  auto finished = [&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (journal->snapshot_running() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return !journal->snapshot_running();
  };
  edit_many();
  EXPECT_TRUE(journal->snapshot_if_due(/*settled=*/false));  // 200 records: due at once
  ASSERT_TRUE(finished());
  EXPECT_EQ(journal->snapshots(), 1u);
  EXPECT_EQ(journal->journal_records(), 0u);
  EXPECT_EQ(reload(path), document_of(live));

  edit_many();
  {
    FileSizeLimit full(0);  // the snapshot cannot be written; the journal keeps everything
    EXPECT_TRUE(journal->snapshot_if_due(/*settled=*/false));
    ASSERT_TRUE(finished());
    EXPECT_EQ(journal->snapshots(), 1u);
    EXPECT_EQ(journal->journal_records(), SessionJournal::kSnapshotRecords);
    // a failed snapshot is not retried at once, however large the journal
    EXPECT_FALSE(journal->snapshot_if_due(/*settled=*/false));
    EXPECT_FALSE(journal->snapshot_if_due(/*settled=*/true));
  }
  EXPECT_EQ(reload(path), document_of(live));
  journal->snapshot_now();
  EXPECT_EQ(journal->journal_records(), 0u);
  EXPECT_EQ(reload(path), document_of(live));
}

// --- the actor --------------------------------------------------------------------------------

class JournalRecorder final : public server::SessionSubscriber {
 public:
  void send_text(std::string message) override {
    std::lock_guard lock(mutex_);
    texts_.push_back(json::parse(message));
    changed_.notify_all();
  }
  void send_pose(std::string) override {}
  // the `ack` or `error` with this id (waits up to 10 s; null when none came)
  json answer(const json& id) {
    std::unique_lock lock(mutex_);
    json found;
    changed_.wait_for(lock, std::chrono::seconds(10), [&] {
      for (const json& t : texts_) {
        if ((t.at("type") == "ack" || t.at("type") == "error") && t.value("id", json()) == id) {
          found = t;
          return true;
        }
      }
      return false;
    });
    return found;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<json> texts_;
};

TEST(SessionJournal, AnEditThatCannotBeWrittenGetsAnErrorAndIsTakenBackExactly) {
  TempDir dir;
  const std::string path = dir.file("s.json");
  server::SessionActor actor(
      "0123456789abcdef0123456789abcdef",
      std::make_unique<animator::Session>(fixtures::bundled_human48(), "human48"), path);
  auto recorder = std::make_shared<JournalRecorder>();
  actor.subscribe(1, recorder);
  auto post = [&](json m, int id) {
    m["id"] = id;
    actor.post(1, server::parse_client_message(m.dump()));
    return recorder->answer(id);
  };
  auto state = [&] {
    return actor.call([](animator::Session& s) {
      return document_of(s) + json(s.history().undo_labels()).dump();
    });
  };
  ASSERT_EQ(post({{"type", "key_insert"}, {"time", 0}}, 1).at("type"), "ack");
  ASSERT_EQ(post({{"type", "key_insert"}, {"time", 1}}, 2).at("type"), "ack");
  ASSERT_EQ(post({{"type", "undo"}}, 3).at("type"), "ack");  // a redo entry to keep
  const std::string before = state();
  {
    FileSizeLimit full(0);
    for (const json& m :
         {json{{"type", "pin"}, {"link", "l_foot"}}, json{{"type", "key_insert"}, {"time", 2}},
          json{{"type", "undo"}}, json{{"type", "set_falloff"}, {"seconds", 1.5}}}) {
      const json answer = post(m, 10);
      ASSERT_EQ(answer.value("type", ""), "error") << m << " -> " << answer;
      EXPECT_EQ(answer.value("code", ""), "not_saved");
      EXPECT_NE(answer.at("message").get<std::string>().find(m.at("type").get<std::string>() +
                                                             ": not saved (File too large)"),
                std::string::npos)
          << answer;
      EXPECT_EQ(state(), before) << m;
      recorder = std::make_shared<JournalRecorder>();
      actor.subscribe(1, recorder);
    }
    // an edit by call() (an HTTP upload) throws, and is taken back too
    try {
      actor.call([](animator::Session& s) { s.key_insert(3.0); }, /*edit=*/true);
      ADD_FAILURE() << "an edit that could not be saved returned";
    } catch (const animator::SessionWriteError& e) {
      EXPECT_TRUE(e.out_of_space());
    }
    EXPECT_EQ(state(), before);
    EXPECT_GE(actor.stats().save_failures, 5u);
  }
  // with room again the history is the one before: redo brings back the key at 1 s
  ASSERT_EQ(post({{"type", "redo"}}, 20).at("type"), "ack");
  const std::size_t keys = actor.call([](animator::Session& s) { return s.keys().keys().size(); });
  EXPECT_EQ(keys, 2u);
  const std::string saved = actor.call([](animator::Session& s) { return document_of(s); });
  actor.stop();
  EXPECT_EQ(reload(path), saved);
}

}  // namespace
