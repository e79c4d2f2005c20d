// Tests for animator/session.hpp: gestures, pins, keys, playback, recording, editing in motion,
// undo/redo and persistence.
#include "animator/session.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <numbers>
#include <random>

#include "animator/session_file.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "tests/animator/animator_fixtures.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace animator;
using core::Quaternion;
using core::Vector3;

using animator_test::human;
using animator_test::position;
using animator_test::run;
using animator_test::swinging_clip;

TEST(Session, DragGestureMovesTheHandAndIsOneUndoEntry) {
  Session s(human(), "human48");
  const int hand = s.model().link_index("r_hand");
  const Eigen::VectorXd q0 = s.q();
  const Vector3 start = position(s, "r_hand");
  s.drag_begin(hand, start);
  for (int k = 1; k <= 30; ++k) {
    s.drag_move(start + Vector3(-0.01 * k, 0.01 * k, 0.005 * k));
    s.tick(1.0 / 60);
  }
  run(s, 30);
  s.drag_end();
  EXPECT_LT((position(s, "r_hand") - (start + Vector3(-0.3, 0.3, 0.15))).norm(), 1e-3);
  EXPECT_EQ(s.history().size(), 1u);
  const Eigen::VectorXd q1 = s.q();
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.q(), q0);
  ASSERT_TRUE(s.redo());
  EXPECT_EQ(s.q(), q1);
  EXPECT_FALSE(s.redo());
}

TEST(Session, PinnedFeetStayWhileTheHandIsDragged) {
  Session s(human(), "human48");
  const int lf = s.model().link_index("l_foot"), rf = s.model().link_index("r_foot");
  s.pin(lf, ik::TaskMode::kPose);
  s.pin(rf, ik::TaskMode::kPose);
  const Vector3 l0 = position(s, "l_foot"), r0 = position(s, "r_foot");
  const int hand = s.model().link_index("r_hand");
  const Vector3 start = position(s, "r_hand");
  s.drag_begin(hand, start);
  for (int k = 1; k <= 40; ++k) {
    s.drag_move(start + Vector3(0, -0.008 * k, 0.004 * k));  // reach down and forward
    s.tick(1.0 / 60);
  }
  s.drag_end();
  run(s, 120);
  EXPECT_LT((position(s, "l_foot") - l0).norm(), 1e-3);
  EXPECT_LT((position(s, "r_foot") - r0).norm(), 1e-3);
  EXPECT_FALSE(s.needs_tick());  // settled
}

TEST(Session, BadRequestsAreRefusedWithoutChangingAnything) {
  Session s(human(), "human48");
  const nlohmann::json before = session_to_json(s);
  EXPECT_THROW(s.drag_begin(0, Vector3::Zero()), SessionError);
  EXPECT_THROW(s.drag_begin(999, Vector3::Zero()), SessionError);
  EXPECT_THROW(s.drag_begin(2, Vector3(NAN, 0, 0)), SessionError);
  EXPECT_THROW(s.drag_move(Vector3::Zero()), SessionError);
  EXPECT_THROW(s.unpin(3), SessionError);
  EXPECT_THROW(s.key_delete(0), SessionError);
  EXPECT_THROW(s.seek(INFINITY), SessionError);
  ik::SolverSettings bad;
  bad.damping = -1;
  EXPECT_THROW(s.set_solver_settings(bad), SessionError);
  try {
    s.drag_begin(999, Vector3::Zero());
  } catch (const SessionError& e) {
    EXPECT_NE(std::string(e.what()).find("link: link index 999 is out of range"),
              std::string::npos);
  }
  EXPECT_EQ(session_to_json(s), before);
  EXPECT_EQ(s.history().size(), 0u);
}

TEST(Session, KeysInterpolateAndPlayBack) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  const int elbow = m.link_index("r_farm");
  s.key_insert(0.0);
  Eigen::VectorXd q = s.q();
  const double e0 = q[m.idx_q[elbow]];  // the rest pose's elbow
  q[m.idx_q[elbow]] = 1.2;
  s.set_pose(q);
  s.key_insert(1.0, Interpolation::kLinear);
  ASSERT_EQ(s.keys().keys().size(), 2u);
  s.seek(0.5);
  EXPECT_NEAR(s.q()[m.idx_q[elbow]], 0.5 * (e0 + 1.2),
              1e-9);  // smooth from key 0: symmetric Hermite midpoint
  s.play();
  run(s, 15);
  EXPECT_NEAR(s.playback().time, 0.75, 1e-9);
  s.pause();
  // step interpolation holds the first key
  s.key_set_interpolation(0, Interpolation::kStep);
  s.seek(0.9);
  EXPECT_EQ(s.q()[m.idx_q[elbow]], e0);
  s.bake_keys(30);
  ASSERT_NE(s.clip(), nullptr);
  EXPECT_EQ(s.clip()->size(), 31);
}

TEST(Session, RecordingBecomesTheClip) {
  Session s(human(), "human48");
  const int hand = s.model().link_index("l_hand");
  const Vector3 start = position(s, "l_hand");
  s.record(true);
  s.drag_begin(hand, start);
  for (int k = 1; k <= 60; ++k) {
    s.drag_move(start + Vector3(0.003 * k, 0.004 * k, 0));
    s.tick(1.0 / 60);
  }
  s.drag_end();
  s.record(false);
  ASSERT_NE(s.clip(), nullptr);
  EXPECT_EQ(s.clip()->size(), 31);  // 1 s at 30 fps plus the first frame
  EXPECT_NEAR(s.clip()->frame_time, 1.0 / 30, 1e-15);
  EXPECT_NE(s.clip()->frames.front(), s.clip()->frames.back());
}

TEST(Session, PlaybackLoopsAndRespectsSpeed) {
  Session s(human(), "human48");
  s.set_clip(swinging_clip(s.model()));
  const double length = s.duration();
  s.set_loop(true);
  s.set_speed(2.0);
  s.play();
  run(s, 45, 1.0 / 30);  // 1.5 s of wall time at double speed = 3 s of a 1.97 s clip
  EXPECT_NEAR(s.playback().time, std::fmod(3.0, length), 1e-9);
  s.set_loop(false);
  run(s, 60, 1.0 / 30);
  EXPECT_FALSE(s.playback().playing);
  EXPECT_NEAR(s.playback().time, length, 1e-12);
}

TEST(Session, EditingInMotionKeepsPinnedFeetAndLeavesOtherFramesUntouched) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  const core::Clip base = swinging_clip(m, 90);
  s.set_clip(base);
  s.pin(m.link_index("l_foot"), ik::TaskMode::kPose);
  s.pin(m.link_index("r_foot"), ik::TaskMode::kPose);
  s.set_edit_falloff(0.2);
  s.set_loop(false);
  s.seek(1.0);
  s.play();
  const int hand = m.link_index("r_hand");
  const Vector3 start = position(s, "r_hand");
  s.drag_begin(hand, start);
  core::Data ref(m);
  double foot_drift = 0;
  for (int k = 1; k <= 20; ++k) {
    s.drag_move(start + Vector3(-0.004 * k, 0.006 * k, 0.004 * k));
    s.tick(1.0 / 30);
    // the feet follow the clip's feet (moving pins)
    core::forward_kinematics(m, ref, base.frames[std::lround(s.playback().time * 30)]);
    for (const char* foot : {"l_foot", "r_foot"}) {
      foot_drift = std::max(foot_drift, (position(s, foot) - ref.X_W[m.link_index(foot)].p).norm());
    }
  }
  s.drag_end();
  s.pause();
  ASSERT_EQ(s.layers().size(), 1u);
  EXPECT_LT(foot_drift, 1e-3);
  const EditLayer& layer = *s.layers()[0];
  EXPECT_EQ(layer.first_frame, 31);
  EXPECT_EQ(layer.last_frame(), 50);
  // outside the edited frames and the falloff (0.2 s = 6 frames) the motion is bit-identical
  const core::Clip edited = s.animation_clip();
  for (int f = 0; f < base.size(); ++f) {
    const bool outside = f < layer.first_frame - 6 || f > layer.last_frame() + 6;
    if (outside) {
      EXPECT_EQ(std::memcmp(edited.frames[f].data(), base.frames[f].data(), sizeof(double) * m.nq),
                0)
          << f;
    }
  }
  EXPECT_NE(edited.frames[40], base.frames[40]);
  // muting restores the base; the edit is undoable as one entry
  s.set_layer_muted(0, true);
  EXPECT_EQ(s.animation_clip().frames[40], base.frames[40]);
  s.undo();
  EXPECT_EQ(s.animation_clip().frames[40], edited.frames[40]);
}

// A drag over a paused clip edits the frame shown. Pins are moving pins there too: a drag at frame
// 8 keeps the pinned links where the clip has them at frame 8, not where they were when pinned at
// frame 0; the edit is kept as a layer on that frame.
TEST(Session, PinsOverAPausedClipHoldWhereTheClipHasThemAtTheFrameShown) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  const core::Clip base = swinging_clip(m, 60);
  s.set_clip(base);
  s.seek(0.0);
  s.pin(m.link_index("l_foot"), ik::TaskMode::kPose);
  s.pin(m.link_index("r_hand"), ik::TaskMode::kPosition);
  s.seek(8.0 / 30);
  const Vector3 foot = position(s, "l_foot");
  const Vector3 hand = position(s, "r_hand");
  ASSERT_GT((hand - s.pins()[1].target_W).norm(), 0.01) << "the clip must move the pinned hand";
  const Vector3 start = position(s, "l_hand");
  s.drag_begin(m.link_index("l_hand"), start);
  double drift = 0;
  for (int k = 1; k <= 20; ++k) {
    s.drag_move(start + Vector3(0, 0.005 * k, 0.003 * k));
    s.tick(1.0 / 60);
    drift = std::max(
        {drift, (position(s, "l_foot") - foot).norm(), (position(s, "r_hand") - hand).norm()});
  }
  const Vector3 dragged = position(s, "l_hand");
  s.drag_end();
  EXPECT_LT(drift, 1e-3);
  EXPECT_GT((dragged - start).norm(), 0.05);
  // the edit is kept: a layer on frame 8 that seeking away and back shows again, one undo entry
  ASSERT_EQ(s.layers().size(), 1u);
  EXPECT_EQ(s.layers()[0]->first_frame, 8);
  EXPECT_EQ(s.layers()[0]->last_frame(), 8);
  s.seek(40.0 / 30);
  s.seek(8.0 / 30);
  EXPECT_LT((position(s, "l_hand") - dragged).norm(), 1e-9);
  const core::Clip edited = s.animation_clip();
  EXPECT_EQ(edited.frames[40], base.frames[40]);  // beyond the falloff: untouched
  s.undo();
  EXPECT_TRUE(s.layers().empty());
}

// Plays a 60-frame looping clip (30 fps, falloff 3 frames) from frame 40 and holds the right hand
// 9 cm off for `ticks` frames; returns the clip.
core::Clip hold_a_drag_over_the_loop(Session& s, int ticks) {
  const core::Clip base = swinging_clip(s.model(), 60);
  s.set_clip(base);
  s.set_edit_falloff(0.1);
  s.set_loop(true);
  s.seek(40.0 / 30);
  s.play();
  const Vector3 start = position(s, "r_hand");
  s.drag_begin(s.model().link_index("r_hand"), start);
  s.drag_move(start + Vector3(0, 0.08, 0.05));
  run(s, ticks, 1.0 / 30);
  s.drag_end();
  s.pause();
  return base;
}

// One gesture makes one layer: a drag held while a looping clip comes round twice is one edit
// over both ends of the loop; the frames between its two passes that it never reached keep the
// clip beyond the falloff.
TEST(Session, AGestureAcrossTheLoopWrapMakesOneLayer) {
  Session s(human(), "human48");
  hold_a_drag_over_the_loop(s, 100);  // frames 41..59, then 0..59 again, then 0..20
  ASSERT_EQ(s.layers().size(), 1u);
  const EditLayer& layer = *s.layers()[0];
  EXPECT_EQ(layer.first_frame, 0);
  EXPECT_EQ(layer.last_frame(), 59);
  for (int f : {5, 30, 50}) EXPECT_GT(layer.displacement[f].norm(), 0.01) << f;
}

// A gesture released before the loop came round again leaves a gap of frames it never reached:
// they ease out from both passes, and the middle of the gap keeps the clip.
TEST(Session, FramesAGestureNeverReachedKeepTheClip) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  const core::Clip base = hold_a_drag_over_the_loop(s, 35);  // frames 41..59, then 0..16
  ASSERT_EQ(s.layers().size(), 1u);
  const EditLayer& layer = *s.layers()[0];
  ASSERT_EQ(layer.first_frame, 0);
  ASSERT_EQ(layer.last_frame(), 59);
  EXPECT_GT(layer.displacement[10].norm(), 0.01);
  EXPECT_GT(layer.displacement[50].norm(), 0.01);
  // the gap 17..40: three frames of ease on each side, the clip itself in between
  for (int f = 21; f <= 36; ++f) EXPECT_EQ(layer.displacement[f].norm(), 0.0) << f;
  EXPECT_GT(layer.displacement[17].norm(), 0.0);
  EXPECT_LT(layer.displacement[17].norm(), layer.displacement[16].norm());
  EXPECT_LT(layer.displacement[40].norm(), layer.displacement[41].norm());
  const core::Clip edited = s.animation_clip();
  for (int f = 21; f <= 36; ++f) {
    EXPECT_LT(core::difference(m, base.frames[f], edited.frames[f]).norm(), 1e-12) << f;
  }
}

// The real-clip check: a CMU walk (31 joints, 120 fps), both feet moving pins while the
// right hand is dragged 12 cm away from where the clip has it, for half a second of playback.
TEST(Session, EditingInMotionOnARealCmuClipKeepsTheFeetWithinAMillimetre) {
  PINDRAG_REQUIRE_DATA_DIR();
  const io::BvhImport imp = io::load_bvh_file(fixtures::data_dir() + "/bvh/cmu_walk_cgspeed.bvh");
  Session s(imp.model, "cmu_walk_cgspeed");
  const core::Model& m = s.model();
  const core::Clip& base = imp.clip;
  ASSERT_EQ(m.njoints - 1, 31 + 7);  // 31 joints and 7 End Sites
  const double ft = base.frame_time;
  s.set_clip(base);
  const int first = 100, frames = 60;
  s.seek(first * ft);
  const std::vector<int> feet = {m.link_index("LeftFoot"), m.link_index("RightFoot")};
  for (int foot : feet) s.pin(foot, ik::TaskMode::kPose);
  s.set_edit_falloff(0.1);
  s.set_loop(false);
  s.play();
  const int hand = m.link_index("RightHand");
  core::Data ref(m);
  const Vector3 offset(0.0, 0.08, 0.09);  // up and forward, 12 cm
  s.drag_begin(hand, position(s, "RightHand"));
  double foot_drift = 0, hand_error = 0;
  for (int k = 1; k <= frames; ++k) {
    core::forward_kinematics(m, ref, base.frames[first + k]);
    const double ramp = std::min(1.0, k / 20.0);  // the hand leaves the clip over 20 frames
    s.drag_move(ref.X_W[hand].p + ramp * offset);
    s.tick(ft);
    ASSERT_EQ(std::lround(s.playback().time / ft), first + k);
    for (int foot : feet) {
      foot_drift = std::max(foot_drift, (s.kinematics().X_W[foot].p - ref.X_W[foot].p).norm());
    }
    if (k == frames) hand_error = (s.kinematics().X_W[hand].p - (ref.X_W[hand].p + offset)).norm();
  }
  s.drag_end();
  s.pause();
  EXPECT_LE(foot_drift, 1e-3);
  EXPECT_LT(hand_error, 0.02) << "the drag must move the hand";
  ASSERT_EQ(s.layers().size(), 1u);
  const EditLayer& layer = *s.layers()[0];
  EXPECT_EQ(layer.first_frame, first + 1);
  EXPECT_EQ(layer.last_frame(), first + frames);
  // the kept motion: the feet stay on the clip's feet over the edited frames
  const core::Clip edited = s.animation_clip();
  core::Data got(m);
  double kept_drift = 0;
  for (int f = layer.first_frame; f <= layer.last_frame(); ++f) {
    core::forward_kinematics(m, got, edited.frames[f]);
    core::forward_kinematics(m, ref, base.frames[f]);
    for (int foot : feet)
      kept_drift = std::max(kept_drift, (got.X_W[foot].p - ref.X_W[foot].p).norm());
  }
  EXPECT_LE(kept_drift, 1e-3);
  // reported, not asserted: the fade in and out blends the edge displacement without the pins
  const int falloff_frames = static_cast<int>(std::ceil(0.1 / ft));
  double fade_drift = 0;
  for (int f = layer.first_frame - falloff_frames; f <= layer.last_frame() + falloff_frames; ++f) {
    if (f >= layer.first_frame && f <= layer.last_frame()) continue;
    core::forward_kinematics(m, got, edited.frames[f]);
    core::forward_kinematics(m, ref, base.frames[f]);
    for (int foot : feet)
      fade_drift = std::max(fade_drift, (got.X_W[foot].p - ref.X_W[foot].p).norm());
  }
  std::printf(
      "CMU walk edit: foot drift %.3f mm live, %.3f mm kept, %.3f mm in the fades; hand %.1f mm "
      "from its target\n",
      1e3 * foot_drift, 1e3 * kept_drift, 1e3 * fade_drift, 1e3 * hand_error);
  // outside the edited frames and the falloff (0.1 s = 12 frames) the motion is bit-identical
  int identical = 0;
  for (int f = 0; f < base.size(); ++f) {
    if (f >= layer.first_frame - falloff_frames && f <= layer.last_frame() + falloff_frames)
      continue;
    ASSERT_EQ(std::memcmp(edited.frames[f].data(), base.frames[f].data(), sizeof(double) * m.nq), 0)
        << f;
    ++identical;
  }
  EXPECT_GT(identical, base.size() - frames - 2 * falloff_frames - 3);
}

TEST(Session, UndoRedoOfAThousandRandomEditsRestoresSerializedStatesExactly) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1, 1);
  auto state = [&] { return session_to_json(s, /*include_character=*/false).dump(); };
  std::vector<std::string> states{state()};
  const std::vector<const char*> links = {"r_hand", "l_hand", "head", "pelvis",
                                          "l_foot", "r_foot", "chest"};
  for (int e = 0; e < 1000; ++e) {
    const int link = m.link_index(links[rng() % links.size()]);
    const size_t before = s.history().size();
    switch (rng() % 6) {
      case 0: {  // a short drag gesture
        const Vector3 p = s.kinematics().X_W[link].p;
        s.drag_begin(link, p);
        for (int k = 0; k < 3; ++k) {
          s.drag_move(p + 0.05 * Vector3(u(rng), u(rng), u(rng)));
          s.tick(1.0 / 60);
        }
        s.drag_end();
        break;
      }
      case 1:
        s.pin(link, rng() % 2 ? ik::TaskMode::kPose : ik::TaskMode::kPosition);
        break;
      case 2:
        if (!s.pins().empty())
          s.unpin(s.pins()[rng() % s.pins().size()].link);
        else
          s.key_insert(std::abs(u(rng)) * 3);
        break;
      case 3:
        s.key_insert(std::abs(u(rng)) * 3);
        break;
      case 4:
        if (!s.keys().empty())
          s.key_delete(static_cast<int>(rng() % s.keys().keys().size()));
        else
          s.key_insert(0.5);
        break;
      case 5: {
        ik::SolverSettings st = s.solver_settings();
        st.damping = 0.01 + 0.05 * std::abs(u(rng));
        s.set_solver_settings(st);
        break;
      }
    }
    // settle between edits so the next gesture starts from rest (no extra entries)
    run(s, 2);
    if (s.history().size() > before)
      states.push_back(state());
    else
      states.back() = state();
  }
  // every committed entry restores its serialized state exactly
  const size_t entries = s.history().size();
  ASSERT_EQ(states.size(), entries + 1);
  // undo all: each step restores exactly the state before that edit; redo all: exactly after
  for (size_t k = 0; k < entries; ++k) {
    ASSERT_TRUE(s.undo());
    EXPECT_EQ(state(), states[entries - 1 - k]) << "undo " << k;
  }
  EXPECT_FALSE(s.undo());
  for (size_t k = 0; k < entries; ++k) {
    ASSERT_TRUE(s.redo());
    EXPECT_EQ(state(), states[k + 1]) << "redo " << k;
  }
  EXPECT_FALSE(s.redo());
}

TEST(Session, SavesAndLoadsIdentically) {
  Session s(human(), "human48");
  const core::Model& m = s.model();
  s.set_clip(swinging_clip(m));
  s.pin(m.link_index("l_foot"), ik::TaskMode::kPose);
  s.key_insert(0.25);
  s.seek(0.5);
  s.play();
  const Vector3 start = position(s, "r_hand");
  s.drag_begin(m.link_index("r_hand"), start);
  for (int k = 0; k < 5; ++k) {
    s.drag_move(start + Vector3(0, 0.01 * k, 0));
    s.tick(1.0 / 30);
  }
  s.drag_end();
  s.pause();
  const std::string path =
      (std::filesystem::temp_directory_path() / "pindrag_session_test.json").string();
  save_session(s, path);
  const auto loaded = load_session(path);
  EXPECT_EQ(session_to_json(*loaded).dump(), session_to_json(s).dump());
  EXPECT_TRUE(loaded->model() == s.model());
  std::filesystem::remove(path);
  // a damaged file is refused with the field named
  nlohmann::json j = session_to_json(s);
  j["pins"][0]["link"] = "nope";
  try {
    session_from_json(j, "test");
    FAIL();
  } catch (const SessionError& e) {
    EXPECT_NE(std::string(e.what()).find("/pins/0/link: unknown link 'nope'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
