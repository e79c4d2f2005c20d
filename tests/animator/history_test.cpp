// Tests for animator/history.hpp: entries hold differences (not copies of the document), the
// memory they hold is counted in bytes and bounded by the budget, and undo/redo restore exactly.
#include "animator/history.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "animator/session.hpp"
#include "animator/session_file.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using namespace animator;
using animator_test::human;
using animator_test::position;
using animator_test::run;
using animator_test::swinging_clip;

std::string serialized_state(const Session& s) {
  return session_to_json(s, /*include_character=*/false).dump();
}

// bytes of one stored key of the figure (its configuration and the Keyframe itself)
std::size_t key_bytes() { return sizeof(Keyframe) + sizeof(double) * human()->nq; }

TEST(History, AKeyEditOnAThousandsOfKeysTrackHoldsOnlyThatKey) {
  Session s(human(), "human48");
  Document doc = s.document();
  for (int k = 0; k < 3000; ++k) doc.keys.insert(Keyframe{k * 0.01, doc.q});
  s.restore(doc, Playback{});  // 3000 keys, an empty history
  s.key_insert(100.0);
  const std::size_t entry = s.history().bytes();
  // the entry: two poses, the added key and fixed parts; never the 3000 other keys
  EXPECT_GT(entry, key_bytes());
  EXPECT_LT(entry, 10 * key_bytes()) << entry;
  s.key_delete(1234);
  EXPECT_LT(s.history().bytes() - entry, 10 * key_bytes());
  // a pin entry holds no key at all
  const std::size_t before_pin = s.history().bytes();
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  EXPECT_LT(s.history().bytes() - before_pin, 5 * key_bytes());
  EXPECT_EQ(s.history().size(), 3u);
  ASSERT_TRUE(s.undo());
  ASSERT_TRUE(s.undo());
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.keys().keys(), doc.keys.keys());
}

// The case: 3,000 keys and thousands of key edits kept 4.1 GB of copies; now the history
// stays under its budget, and what it keeps undoes exactly.
TEST(History, ThreeThousandKeysAndManyEditsStayUnderTheUndoBudget) {
  Session s(human(), "human48");
  Limits limits;
  limits.max_undo_bytes = std::size_t{4} << 20;
  s.set_limits(limits);
  for (int k = 0; k < 3000; ++k) s.key_insert(k * 0.01);
  std::size_t peak = 0;
  for (int e = 0; e < 1500; ++e) {
    const int index = (e * 7919) % s.keys().size();
    if (e % 3 == 0) {
      s.key_move(index, 30.0 + e * 0.001);
    } else if (e % 3 == 1) {
      s.key_set_interpolation(index, e % 2 ? Interpolation::kLinear : Interpolation::kStep);
    } else {
      s.key_insert(40.0 + e * 0.001);
    }
    peak = std::max(peak, s.history().bytes());
  }
  std::printf(
      "3000 keys, 1500 key edits: undo history peak %zu bytes (budget %zu), %zu entries "
      "kept, %zu dropped\n",
      peak, limits.max_undo_bytes, s.history().size(), s.history().dropped());
  EXPECT_LE(peak, limits.max_undo_bytes);
  EXPECT_GT(s.history().dropped(), 0u);
  EXPECT_GT(s.history().size(), 1000u);  // differences are small: many entries fit
  // everything kept undoes and redoes exactly
  const std::string last = serialized_state(s);
  const std::size_t entries = s.history().size();
  for (std::size_t k = 0; k < entries; ++k) ASSERT_TRUE(s.undo());
  EXPECT_FALSE(s.undo());
  for (std::size_t k = 0; k < entries; ++k) ASSERT_TRUE(s.redo());
  EXPECT_EQ(serialized_state(s), last);
}

TEST(History, OverTheBudgetTheOldestGoFirstAndTheNewestIsKept) {
  Session s(human(), "human48");
  Limits limits;
  limits.max_undo_bytes = 1;  // smaller than any entry
  s.set_limits(limits);
  s.key_insert(0.0);
  s.key_insert(1.0);
  s.pin(s.model().link_index("r_foot"), ik::TaskMode::kPosition);
  EXPECT_EQ(s.history().size(), 1u);
  EXPECT_EQ(s.history().dropped(), 2u);
  EXPECT_EQ(s.history().undo_labels(), std::vector<std::string>{"pin r_foot"});
  ASSERT_TRUE(s.undo());
  EXPECT_TRUE(s.pins().empty());
  EXPECT_EQ(s.keys().size(), 2);  // the dropped entries' edits stay
  EXPECT_FALSE(s.undo());
  // lowering the budget of a full history trims it at once
  Session t(human(), "human48");
  for (int k = 0; k < 50; ++k) t.key_insert(k);
  EXPECT_EQ(t.history().size(), 50u);
  limits.max_undo_bytes = t.history().bytes() / 2;
  t.set_limits(limits);
  EXPECT_LE(t.history().bytes(), limits.max_undo_bytes);
  EXPECT_LT(t.history().size(), 50u);
}

TEST(History, ARedoBranchDroppedByANewEditGivesItsBytesBack) {
  Session s(human(), "human48");
  for (int k = 0; k < 10; ++k) s.key_insert(k);
  const std::size_t full = s.history().bytes();
  for (int k = 0; k < 5; ++k) s.undo();
  EXPECT_EQ(s.history().bytes(), full);  // undone entries are kept for redo
  s.pin(s.model().link_index("head"), ik::TaskMode::kPosition);
  EXPECT_EQ(s.history().size(), 6u);
  EXPECT_LT(s.history().bytes(), full);
}

TEST(History, AReplacedClipIsCountedByTheEntryThatReplacedIt) {
  Session s(human(), "human48");
  s.set_clip(swinging_clip(s.model(), 300), "import clip");
  const std::size_t first = s.history().bytes();
  // the new clip is the document's: its entry holds two poses, not 300 frames
  EXPECT_LT(first, 300 * sizeof(double) * s.model().nq);
  s.set_clip(swinging_clip(s.model(), 30), "import clip");
  // the second entry keeps the first clip alive, and counts it
  EXPECT_GT(s.history().bytes() - first, 300 * sizeof(double) * s.model().nq);
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.clip()->size(), 300);
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.clip(), nullptr);
}

// Entries store whole poses, so undo restores the pose before an edit even when playback moved
// the figure since (as the copies of the whole document did).
TEST(History, UndoRestoresThePoseBeforeTheEditAfterPlaybackMovedIt) {
  Session s(human(), "human48");
  s.set_clip(swinging_clip(s.model()));
  const Eigen::VectorXd q_before = s.q();
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  s.play();
  run(s, 20, 1.0 / 30);
  s.pause();
  ASSERT_NE(s.q(), q_before);
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.q(), q_before);
  EXPECT_TRUE(s.pins().empty());
}

TEST(History, MovesOfOnePinMergeIntoOneEntry) {
  Session s(human(), "human48");
  const int hand = s.model().link_index("r_hand");
  s.pin(hand, ik::TaskMode::kPosition);
  const core::Vector3 start = s.pins()[0].target_W;
  for (int k = 1; k <= 20; ++k) s.move_pin(hand, start + core::Vector3(0, 0.01 * k, 0));
  EXPECT_EQ(s.history().size(), 2u);
  EXPECT_EQ(s.history().undo_labels().back(), "move pin r_hand");
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.pins()[0].target_W, start);
  ASSERT_TRUE(s.redo());
  EXPECT_EQ(s.pins()[0].target_W, start + core::Vector3(0, 0.2, 0));
}

TEST(History, SettlingAfterAnEditBelongsToThatEdit) {
  Session s(human(), "human48");
  const int hand = s.model().link_index("r_hand");
  const core::Vector3 start = position(s, "r_hand");
  s.pin(hand, ik::TaskMode::kPosition);
  s.move_pin(hand, start + core::Vector3(0, 0.1, 0));
  run(s, 120);  // the figure follows the pin, amending the entry
  const Eigen::VectorXd settled = s.q();
  EXPECT_EQ(s.history().size(), 2u);
  s.undo();
  s.redo();
  EXPECT_EQ(s.q(), settled);
}

}  // namespace
