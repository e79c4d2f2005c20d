// Pin strength (docs/ik.md): a session holds pins on level 1 with the drag below them and the
// joint ranges (hard, the default of a new session), or puts pins below an exact drag (soft, as
// in the book). A squat — both feet pinned, the pelvis dragged 0.25 m down in half a second —
// measured on every frame of the gesture.
#include <gtest/gtest.h>

#include <algorithm>
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
};

Squat squat(Session& s, double depth) {
  const char* feet[] = {"l_foot", "r_foot"};
  Vector3 pinned[2];
  for (int k = 0; k < 2; ++k) {
    s.pin(s.model().link_index(feet[k]), ik::TaskMode::kPose);
    pinned[k] = position(s, feet[k]);
  }
  const Vector3 pelvis0 = position(s, "pelvis");
  s.drag_begin(1, pelvis0);
  Squat out;
  for (int frame = 1; frame <= 60; ++frame) {
    s.drag_move(pelvis0 - Vector3(0, depth * std::min(1.0, frame / 30.0), 0));
    s.tick(1.0 / 60);
    for (int k = 0; k < 2; ++k) {
      out.drift = std::max(out.drift, (position(s, feet[k]) - pinned[k]).norm());
    }
    out.range_violation = std::max(out.range_violation, ik::max_range_violation(s.model(), s.q()));
  }
  out.pelvis_drop = pelvis0.y() - position(s, "pelvis").y();
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
