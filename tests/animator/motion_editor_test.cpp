// Tests for animator/motion_editor.hpp: editing in motion frame by frame, without a session.
// Without a drag the edit follows the clip; a drag moves the link while moving pins keep to the
// clip; finish() turns the recorded frames into a layer, filling skipped frames linearly.
#include "animator/motion_editor.hpp"

#include <gtest/gtest.h>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using animator::MotionEditor;
using animator_test::human;
using animator_test::swinging_clip;

animator::Pin pin_of(const core::Model& m, const char* link) {
  return animator::Pin{.link = m.link_index(link), .mode = ik::TaskMode::kPose};
}

TEST(MotionEditor, BeginsOnTheLayeredClipFrame) {
  const core::Model& m = *human();
  const core::Clip clip = swinging_clip(m);
  MotionEditor editor(m, animator::motion_edit_settings(clip.frame_time));
  editor.begin(clip, {}, 17);
  EXPECT_EQ(editor.pose(), clip.frames[17]);
  EXPECT_EQ(editor.finish("nothing", 0.5), nullptr);  // nothing recorded: no layer
}

TEST(MotionEditor, WithoutADragTheEditFollowsTheClip) {
  const core::Model& m = *human();
  const core::Clip clip = swinging_clip(m);
  MotionEditor editor(m, animator::motion_edit_settings(clip.frame_time));
  editor.begin(clip, {}, 10);
  const std::vector<animator::Pin> pins{pin_of(m, "l_foot"), pin_of(m, "r_foot")};
  for (int f = 11; f <= 20; ++f) {
    const Eigen::VectorXd& q = editor.edit(clip, {}, f, pins, std::nullopt);
    EXPECT_LT(core::difference(m, clip.frames[f], q).norm(), 1e-6) << f;
  }
  const auto layer = editor.finish("still", 0.3);
  ASSERT_NE(layer, nullptr);
  EXPECT_EQ(layer->first_frame, 11);
  EXPECT_EQ(layer->last_frame(), 20);
  EXPECT_EQ(layer->name, "still");
  EXPECT_EQ(layer->falloff, 0.3);
  for (const Eigen::VectorXd& d : layer->displacement) EXPECT_LT(d.norm(), 1e-6);
}

TEST(MotionEditor, ADragMovesTheLinkWhileMovingPinsKeepToTheClip) {
  const core::Model& m = *human();
  const core::Clip clip = swinging_clip(m, 90);
  MotionEditor editor(m, animator::motion_edit_settings(clip.frame_time));
  const std::vector<animator::Pin> pins{pin_of(m, "l_foot"), pin_of(m, "r_foot")};
  const int hand = m.link_index("r_hand");
  core::Data ref(m), got(m);
  editor.begin(clip, {}, 30);
  double foot_drift = 0, hand_error = 0;
  for (int f = 31; f <= 60; ++f) {
    core::forward_kinematics(m, ref, clip.frames[f]);
    const core::Vector3 target = ref.X_W[hand].p + core::Vector3(0, 0.06, 0.04);
    ik::LinkTask drag{.role = ik::kDrag, .link = hand, .target_W = target};
    const Eigen::VectorXd& q = editor.edit(clip, {}, f, pins, drag);
    core::forward_kinematics(m, got, q);
    for (const auto& p : pins)
      foot_drift = std::max(foot_drift, (got.X_W[p.link].p - ref.X_W[p.link].p).norm());
    hand_error = (got.X_W[hand].p - target).norm();
  }
  EXPECT_LT(foot_drift, 1e-3);
  EXPECT_LT(hand_error, 0.01);
  const auto layer = editor.finish("reach", 0.5);
  ASSERT_NE(layer, nullptr);
  EXPECT_EQ(layer->first_frame, 31);
  EXPECT_EQ(layer->last_frame(), 60);
  EXPECT_GT(layer->displacement.back().norm(), 0.01);
}

TEST(MotionEditor, SkippedFramesAreFilledLinearlyBetweenRecordedOnes) {
  const core::Model& m = *human();
  const core::Clip clip = swinging_clip(m, 60);
  MotionEditor editor(m, animator::motion_edit_settings(clip.frame_time));
  const int hand = m.link_index("l_hand");
  core::Data ref(m);
  editor.begin(clip, {}, 9);
  for (int f : {10, 14}) {
    core::forward_kinematics(m, ref, clip.frames[f]);
    editor.edit(clip, {}, f, {},
                ik::LinkTask{.role = ik::kDrag,
                             .link = hand,
                             .target_W = ref.X_W[hand].p + core::Vector3(0.05, 0.05, 0)});
  }
  const auto layer = editor.finish("gap", 0.5);
  ASSERT_NE(layer, nullptr);
  ASSERT_EQ(layer->displacement.size(), 5u);  // frames 10..14
  const auto& d = layer->displacement;
  for (int k = 1; k < 4; ++k) {
    const double s = k / 4.0;
    EXPECT_TRUE(d[k].isApprox((1 - s) * d[0] + s * d[4], 1e-12)) << k;
  }
}

}  // namespace
