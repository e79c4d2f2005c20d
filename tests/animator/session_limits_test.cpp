// Tests for the budgets of animator/limits.hpp as the Session applies them: every refusal names
// its limit and the setting that changes it and changes nothing; one frame of the animation is
// sampled without building the clip.
#include <gtest/gtest.h>

#include "animator/session.hpp"
#include "animator/session_file.hpp"
#include "tests/animator/animator_fixtures.hpp"
#include "tests/fixtures/allocation_counter.hpp"

namespace {

using namespace animator;
using animator_test::human;
using animator_test::position;
using animator_test::run;
using animator_test::swinging_clip;

// Runs f, which must throw a BudgetError whose message holds every one of `parts`, and checks
// that the document did not change.
template <class F>
void expect_refused(Session& s, F f, std::initializer_list<const char*> parts) {
  const std::string before = session_to_json(s, false).dump();
  const std::size_t entries = s.history().size();
  try {
    f();
    ADD_FAILURE() << "not refused";
  } catch (const BudgetError& e) {
    for (const char* p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
  EXPECT_TRUE(session_to_json(s, false).dump() == before) << "the document changed";
  EXPECT_EQ(s.history().size(), entries);
}

TEST(SessionLimits, AKeyBeyondTheClipLengthIsRefusedNamingTheLimit) {
  Session s(human(), "human48");
  s.key_insert(0.0);
  expect_refused(s, [&] { s.key_insert(1e6); },
                 {"time: 1000000 s", "limit of 3600 s", "pindrag serve --max-clip-seconds"});
  expect_refused(s, [&] { s.key_move(0, 3600.5); }, {"--max-clip-seconds"});
  s.key_insert(3600.0);  // the limit itself is allowed
  EXPECT_EQ(s.keys().size(), 2);
}

TEST(SessionLimits, KeysBeyondTheCountAreRefusedButReplacingOneIsNot) {
  Session s(human(), "human48");
  Limits l;
  l.max_keys = 3;
  s.set_limits(l);
  for (int k = 0; k < 3; ++k) s.key_insert(k);
  expect_refused(s, [&] { s.key_insert(5.0); },
                 {"3 keys", "pindrag serve --max-keys", "delete keys"});
  s.key_insert(1.0, Interpolation::kLinear);  // replaces the key at 1 s
  EXPECT_EQ(s.keys().keys()[1].interpolation, Interpolation::kLinear);
}

TEST(SessionLimits, ClipsBeyondTheBudgetAreRefusedBeforeTheyAreMade) {
  Session s(human(), "human48");
  Limits l;
  l.max_clip_frames = 50;
  s.set_limits(l);
  expect_refused(s, [&] { s.set_clip(swinging_clip(s.model(), 51)); },
                 {"clip: 51 frames exceed the limit of 50 frames", "--max-clip-frames"});
  s.set_clip(swinging_clip(s.model(), 50));
  l.max_clip_values = 10 * s.model().nq;
  s.set_limits(l);
  expect_refused(s, [&] { s.set_clip(swinging_clip(s.model(), 11)); },
                 {"11 frames ×", "numbers per clip", "--max-clip-values"});
  // keys baked at a high rate: refused before a single frame is sampled
  Session k(human(), "human48");
  k.key_insert(0.0);
  k.key_insert(300.0);
  expect_refused(k, [&] { k.bake_keys(1000); },
                 {"rate: 300001 frames exceed the limit of 216000", "--max-clip-frames"});
}

TEST(SessionLimits, EditingInMotionBeyondTheLayerCountIsRefused) {
  Session s(human(), "human48");
  Limits l;
  l.max_layers = 1;
  s.set_limits(l);
  s.set_clip(swinging_clip(s.model(), 90));
  s.set_loop(false);
  s.play();
  const int hand = s.model().link_index("r_hand");
  s.drag_begin(hand, position(s, "r_hand"));
  run(s, 5, 1.0 / 30);
  s.drag_end();
  ASSERT_EQ(s.layers().size(), 1u);
  expect_refused(s, [&] { s.drag_begin(hand, position(s, "r_hand")); },
                 {"1 edit layers", "pindrag serve --max-layers", "bake or remove"});
  EXPECT_FALSE(s.dragging());
  s.pause();
  // a drag over the paused clip edits its frame as a layer too: refused alike
  expect_refused(s, [&] { s.drag_begin(hand, position(s, "r_hand")); }, {"1 edit layers"});
  s.remove_layer(0);
  s.drag_begin(hand, position(s, "r_hand"));
  s.drag_end();
}

TEST(SessionLimits, RecordingStopsAtTheClipLimitAndBecomesTheClip) {
  Session s(human(), "human48");
  Limits l;
  l.max_clip_seconds = 1.0;  // 31 frames at 30 fps
  s.set_limits(l);
  s.record(true);
  bool committed = false;
  for (int k = 0; k < 200; ++k) committed = s.tick(1.0 / 30).committed || committed;
  EXPECT_TRUE(committed);  // the server saves and tells the page
  EXPECT_FALSE(s.recording());
  ASSERT_NE(s.clip(), nullptr);
  EXPECT_EQ(s.clip()->size(), 31);
}

TEST(SessionLimits, UnusableLimitsAreRefused) {
  Session s(human(), "human48");
  Limits l;
  l.max_keys = 0;
  EXPECT_THROW(s.set_limits(l), SessionError);
  l = Limits{};
  l.max_clip_seconds = NAN;
  EXPECT_THROW(s.set_limits(l), SessionError);
}

// The case: keys at 0 s and at 1,000,000 s (a session made under other limits), then one
// frame: sampled from the keys directly, never by building 3×10⁷ frames.
TEST(SessionLimits, OneFrameOfAVeryLongAnimationIsSampledWithoutBuildingTheClip) {
  Session s(human(), "human48");
  Limits wide;
  wide.max_clip_seconds = 2e6;
  s.set_limits(wide);
  s.key_insert(0.0);
  Eigen::VectorXd q_end = core::random_configuration(s.model(), 3);
  s.set_pose(q_end);
  s.key_insert(1e6, Interpolation::kLinear);
  s.set_limits(Limits{});
  ASSERT_EQ(s.animation_frames(), 30'000'001);
  Eigen::VectorXd q(s.model().nq);
  long long bytes = 0;
  {
    fixtures::AllocationCounter counter;
    s.animation_frame(0, q);
    s.animation_frame(30'000'000, q);
    bytes = counter.bytes();
  }
  EXPECT_LT(bytes, 64 * 1024) << "one frame must not build the clip";
  EXPECT_EQ(q, q_end);
  EXPECT_THROW(s.animation_frame(30'000'001, q), SessionError);
  // the whole animation is over the budget: refused, naming it
  try {
    (void)s.animation_clip();
    ADD_FAILURE() << "not refused";
  } catch (const BudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-clip-seconds"), std::string::npos) << e.what();
  }
  // a range of it is sampled
  const core::Clip part = s.animation_clip(15'000'000, 15'000'009);
  ASSERT_EQ(part.size(), 10);
  s.animation_frame(15'000'004, q);
  EXPECT_EQ(part.frames[4], q);
}

TEST(SessionLimits, FramesSampledOneByOneEqualTheWholeClip) {
  Session s(human(), "human48");
  s.key_insert(0.0);
  s.set_pose(core::random_configuration(s.model(), 5));
  s.key_insert(0.7);
  const core::Clip from_keys = s.animation_clip();
  Eigen::VectorXd q;
  ASSERT_EQ(s.animation_frames(), from_keys.size());
  for (int f = 0; f < from_keys.size(); ++f) {
    s.animation_frame(f, q);
    EXPECT_EQ(q, from_keys.frames[f]) << f;
  }
  s.set_clip(swinging_clip(s.model(), 40));
  s.play();
  s.drag_begin(s.model().link_index("r_hand"), position(s, "r_hand"));
  run(s, 8, 1.0 / 30);
  s.drag_end();
  s.pause();
  ASSERT_EQ(s.layers().size(), 1u);
  const core::Clip layered = s.animation_clip();
  for (int f = 0; f < layered.size(); ++f) {
    s.animation_frame(f, q);
    EXPECT_EQ(q, layered.frames[f]) << f;
  }
}

}  // namespace
