// Pin strength (docs/ik.md): a session holds pins on level 1 with the drag below them and the
// joint ranges (hard, the default of a new session), or puts pins below an exact drag (soft, as
// in the book). A squat — both feet pinned, the pelvis dragged 0.25 m down in half a second —
// measured on every frame of the gesture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "animator_fixtures.hpp"
#include "ik/limits.hpp"

namespace {

using animator::Session;
using animator_test::human;
using animator_test::position;
using core::Vector3;

struct Squat {
  double drift = 0;            // the largest distance of a pinned foot from its pin, any frame
  double pelvis_drop = 0;      // how far the pelvis went down
  double range_violation = 0;  // the largest, any frame (rad)
  double knee_flexion = 0;     // the smaller of the two at the end (rad)
  double hip_flexion = 0;      // the smaller of the two thighs' turn against the pelvis (rad)
  double chest_tilt = 0;       // the chest's orientation at the end against its start (rad)
};

const char* const kFeet[] = {"l_foot", "r_foot"};

// pins a foot in pose where it stands; returns where that is
Vector3 pin_foot(Session& s, const char* foot) {
  s.pin(s.model().link_index(foot), ik::TaskMode::kPose);
  return position(s, foot);
}

Squat squat(Session& s, double depth) {
  const Vector3 pinned[2] = {pin_foot(s, kFeet[0]), pin_foot(s, kFeet[1])};
  const Vector3 pelvis0 = position(s, "pelvis");
  const int chest = s.model().link_index("chest");
  const core::Matrix3 chest0 = s.kinematics().X_W[chest].R;
  // a thigh's direction (hip to knee) in the pelvis frame
  const auto thigh = [&s](const char* hip, const char* knee) {
    const core::Model& m = s.model();
    const core::Data& d = s.kinematics();
    return Vector3(d.X_W[1].R.transpose() *
                   (d.X_W[m.link_index(knee)].p - d.X_W[m.link_index(hip)].p).normalized());
  };
  const Vector3 l_thigh0 = thigh("l_thigh", "l_shank"), r_thigh0 = thigh("r_thigh", "r_shank");
  s.drag_begin(1, pelvis0);
  Squat out;
  for (int frame = 1; frame <= 60; ++frame) {
    s.drag_move(pelvis0 - Vector3(0, depth * std::min(1.0, frame / 30.0), 0));
    s.tick(1.0 / 60);
    for (int k = 0; k < 2; ++k) {
      out.drift = std::max(out.drift, (position(s, kFeet[k]) - pinned[k]).norm());
    }
    out.range_violation = std::max(out.range_violation, ik::max_range_violation(s.model(), s.q()));
  }
  out.pelvis_drop = pelvis0.y() - position(s, "pelvis").y();
  const core::Model& m = s.model();
  out.knee_flexion =
      std::min(s.q()[m.idx_q[m.link_index("l_shank")]], s.q()[m.idx_q[m.link_index("r_shank")]]);
  out.chest_tilt = Eigen::AngleAxisd(chest0.transpose() * s.kinematics().X_W[chest].R).angle();
  out.hip_flexion =
      std::min(std::acos(std::clamp(l_thigh0.dot(thigh("l_thigh", "l_shank")), -1.0, 1.0)),
               std::acos(std::clamp(r_thigh0.dot(thigh("r_thigh", "r_shank")), -1.0, 1.0)));
  s.drag_end();
  return out;
}

TEST(PinStrength, ANewSessionsPinsHoldThroughASquat) {
  Session s(human(), "human48");
  ASSERT_TRUE(s.solver_settings().hard_pins);
  const Squat r = squat(s, 0.25);
  std::printf("hard pins: largest foot drift %.2f mm, pelvis down %.0f mm, range violation %.4f\n",
              1e3 * r.drift, 1e3 * r.pelvis_drop, r.range_violation);
  EXPECT_LT(r.drift, 0.001);
  // flat feet stop the squat where the ankles reach their range: the drag is best effort
  EXPECT_LT(r.range_violation, 1e-3);
  EXPECT_GT(r.pelvis_drop, 0.15);
}

// Joint references toward the posture the gesture began in (Yamane eq. 8.22, "Rest gain" in the
// page) and the root's orientation as a reference: the squat bends the knees and keeps the
// torso about as it was; without them the pelvis tips forward with the thighs.
TEST(PinStrength, RestGainKeepsTheTorsoUprightInASquat) {
  Session with(human(), "human48");
  const Squat r = squat(with, 0.12);  // a squat the ankles allow: the drag is met
  Session without(human(), "human48");
  ik::SolverSettings settings = without.solver_settings();
  settings.reference_gain = 0;
  without.set_solver_settings(settings);
  const Squat r0 = squat(without, 0.12);
  std::printf(
      "rest gain %.1f: knees %.2f rad, hips %.2f rad, chest tilted %.3f rad; rest gain 0: knees "
      "%.2f rad, hips %.2f rad, chest tilted %.3f rad\n",
      with.solver_settings().reference_gain, r.knee_flexion, r.hip_flexion, r.chest_tilt,
      r0.knee_flexion, r0.hip_flexion, r0.chest_tilt);
  EXPECT_NEAR(r.pelvis_drop, 0.12, 0.005);
  EXPECT_GT(r.knee_flexion, 0.6) << "the knees bend";
  EXPECT_GT(r.hip_flexion, 0.3) << "the hips bend";
  EXPECT_LT(r.chest_tilt, 0.15) << "the torso stays about as it was";
  EXPECT_LT(r.chest_tilt, 0.5 * r0.chest_tilt) << "the references make the difference";
  EXPECT_LT(r.drift, 0.001);
}

TEST(PinStrength, SoftPinsGiveWayToTheDrag) {
  Session s(human(), "human48");
  ik::SolverSettings settings = s.solver_settings();
  settings.hard_pins = false;
  s.set_solver_settings(settings);
  const Squat r = squat(s, 0.25);
  std::printf("soft pins: largest foot drift %.1f mm, pelvis down %.0f mm\n", 1e3 * r.drift,
              1e3 * r.pelvis_drop);
  EXPECT_NEAR(r.pelvis_drop, 0.25, 0.01) << "the exact drag reached";
  EXPECT_GT(r.drift, 0.05);
}

}  // namespace

namespace {

struct Hold {
  double drift = 0;        // a pinned foot from its pin, any frame (m)
  double joint_speed = 0;  // the fastest joint over the hold's second half (rad/s)
  double hand_motion = 0;  // how far the hand moved over the hold's second half (m)
  double reach_error = 0;  // hand to target at the end (m)
};

// both feet pinned, a hand pulled `far` metres sideways in half a second and then held there
Hold hold_out_of_reach(Session& s, const Vector3& far) {
  const Vector3 pinned[2] = {pin_foot(s, kFeet[0]), pin_foot(s, kFeet[1])};
  const Vector3 hand0 = position(s, "r_hand");
  s.drag_begin(s.model().link_index("r_hand"), hand0);
  Hold out;
  Vector3 hand_mid = hand0;
  constexpr double kDt = 1.0 / 60;
  for (int frame = 1; frame <= 150; ++frame) {
    s.drag_move(hand0 + far * std::min(1.0, frame / 30.0));
    const Eigen::VectorXd before = s.q();
    s.tick(kDt);
    for (int k = 0; k < 2; ++k) {
      out.drift = std::max(out.drift, (position(s, kFeet[k]) - pinned[k]).norm());
    }
    if (frame == 90) hand_mid = position(s, "r_hand");
    if (frame > 90) {
      Eigen::VectorXd dq(s.model().nv);
      core::difference(s.model(), before, s.q(), dq);
      const double v = dq.cwiseAbs().maxCoeff() / kDt;
      out.joint_speed = std::max(out.joint_speed, v);
    }
  }
  out.hand_motion = (position(s, "r_hand") - hand_mid).norm();
  out.reach_error = (position(s, "r_hand") - (hand0 + far)).norm();
  s.drag_end();
  return out;
}

// An unreachable drag leaves the pins where they are and the hand stops at the nearest point it
// can reach, calmly: held still, the figure comes to rest instead of moving on the step limit.
TEST(PinStrength, AnOutOfReachDragIsHeldCalmly) {
  for (const Vector3& far : {Vector3(2.0, 0, 0), Vector3(0, 2.0, 0), Vector3(0, -1.5, 0.8)}) {
    Session s(human(), "human48");
    const Hold h = hold_out_of_reach(s, far);
    std::printf(
        "out of reach (%.1f, %.1f, %.1f): pin drift %.3f mm, joint speed %.4f rad/s, hand "
        "moved %.3f mm over the last second, %.2f m short\n",
        far.x(), far.y(), far.z(), h.drift * 1e3, h.joint_speed, h.hand_motion * 1e3,
        h.reach_error);
    EXPECT_LT(h.drift, 1e-3);
    EXPECT_LT(h.joint_speed, 0.05);
    EXPECT_LT(h.hand_motion, 1e-3);
  }
}

}  // namespace
