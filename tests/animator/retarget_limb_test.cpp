// Retargeting's limb swivel (animator/retarget.cpp, PoseMapper::swivel_into_range): a foot turned
// out further than the target's ankle allows keeps its orientation, and the leg turns about the
// line from hip to ankle to carry the rest of the turn at the hip.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "animator/retarget.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/swing_twist.hpp"
#include "ik/limits.hpp"

namespace {

using core::Quaternion;
using core::Vector3;

constexpr double kDegree = std::numbers::pi / 180;

// A clip of the bundled figure standing still, knees bent by 10 degrees, with its left foot
// turned out (toes toward +x, about the vertical) by `toe_out` at the ankle.
core::Clip standing_with_left_foot_turned_out(const core::Model& m, double toe_out) {
  Eigen::VectorXd q = core::neutral_configuration(m);
  for (const char* knee : {"l_shank", "r_shank"}) q[m.idx_q[m.link_index(knee)]] = 10 * kDegree;
  core::set_quaternion_at(q, m.idx_q[m.link_index("l_foot")],
                          Quaternion(Eigen::AngleAxisd(toe_out, Vector3::UnitY())));
  core::Clip clip;
  clip.frame_time = 1.0 / 30;
  clip.frames.assign(12, q);
  return clip;
}

double angle_between(const core::Matrix3& a, const core::Matrix3& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

TEST(RetargetLimbs, AFootTurnedOutBeyondTheAnkleTurnsTheLegAndKeepsTheFoot) {
  const auto m = core::build_human_figure({});
  const int foot = m->link_index("l_foot"), thigh = m->link_index("l_thigh");
  // 25 degrees of toe-out at the ankle, whose range allows 10 (docs/human-figure.md)
  const core::Clip clip = standing_with_left_foot_turned_out(*m, 25 * kDegree);
  ASSERT_FALSE(
      core::joint_range_status(*m, foot, core::quaternion_at(clip.frames[0], m->idx_q[foot]))
          .inside);
  const animator::RetargetResult r = animator::retarget(*m, clip, *m);
  ASSERT_EQ(r.clip.size(), clip.size());
  EXPECT_EQ(r.report.frames_out_of_range, 0);
  core::Data src(*m), out(*m);
  core::forward_kinematics(*m, src, clip.frames[0]);
  for (int f = 0; f < r.clip.size(); ++f) {
    core::forward_kinematics(*m, out, r.clip.frames[f]);
    // the foot points where the source's does, and stands where it stood
    EXPECT_LT(angle_between(out.X_W[foot].R, src.X_W[foot].R), 1 * kDegree) << "frame " << f;
    EXPECT_LT((out.X_W[foot].p - src.X_W[foot].p).norm(), 0.005) << "frame " << f;
    // the hip carries the turn the ankle lacks: the thigh turned out (toward +x) about the
    // vertical by at least the 15 degrees beyond the ankle's range
    const Vector3 knee_forward = out.X_W[thigh].R * Vector3::UnitZ();
    EXPECT_GT(std::atan2(knee_forward.x(), knee_forward.z()), 14 * kDegree) << "frame " << f;
    EXPECT_LE(ik::max_range_violation(*m, r.clip.frames[f]), animator::kRangeTolerance);
  }
}

TEST(RetargetLimbs, AFootWithinItsRangeLeavesTheLegAsTheSourceHasIt) {
  const auto m = core::build_human_figure({});
  const int thigh = m->link_index("l_thigh"), foot = m->link_index("l_foot");
  const core::Clip clip = standing_with_left_foot_turned_out(*m, 5 * kDegree);
  const animator::RetargetResult r = animator::retarget(*m, clip, *m);
  core::Data src(*m), out(*m);
  core::forward_kinematics(*m, src, clip.frames[0]);
  for (int f = 0; f < r.clip.size(); ++f) {
    core::forward_kinematics(*m, out, r.clip.frames[f]);
    EXPECT_LT(angle_between(out.X_W[thigh].R, src.X_W[thigh].R), 0.5 * kDegree) << "frame " << f;
    EXPECT_LT(angle_between(out.X_W[foot].R, src.X_W[foot].R), 0.5 * kDegree) << "frame " << f;
  }
}

}  // namespace
