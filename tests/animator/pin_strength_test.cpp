// Pin strength (docs/ik.md): a session puts pins beside the drag on level 1 (hard, the default of
// a new session) or below it on level 3 (soft, as in the book). A squat — both feet pinned, the
// pelvis dragged 0.25 m down in half a second — measured on every frame of the gesture.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "animator_fixtures.hpp"

namespace {

using animator::Session;
using animator_test::human;
using animator_test::position;
using core::Vector3;

// the largest distance of a pinned foot from where it was pinned, over every frame of the squat
double squat_pin_drift(Session& s) {
  const char* feet[] = {"l_foot", "r_foot"};
  Vector3 pinned[2];
  for (int k = 0; k < 2; ++k) {
    s.pin(s.model().link_index(feet[k]), ik::TaskMode::kPose);
    pinned[k] = position(s, feet[k]);
  }
  const Vector3 pelvis0 = position(s, "pelvis");
  s.drag_begin(1, pelvis0);
  double drift = 0;
  for (int frame = 1; frame <= 60; ++frame) {
    s.drag_move(pelvis0 - Vector3(0, 0.25 * std::min(1.0, frame / 30.0), 0));
    s.tick(1.0 / 60);
    for (int k = 0; k < 2; ++k) drift = std::max(drift, (position(s, feet[k]) - pinned[k]).norm());
  }
  EXPECT_NEAR(position(s, "pelvis").y(), pelvis0.y() - 0.25, 0.01) << "the squat reached";
  s.drag_end();
  return drift;
}

TEST(PinStrength, ANewSessionsPinsHoldThroughASquat) {
  Session s(human(), "human48");
  ASSERT_TRUE(s.solver_settings().hard_pins);
  const double drift = squat_pin_drift(s);
  std::printf("hard pins: largest foot drift %.1f mm\n", 1e3 * drift);
  EXPECT_LT(drift, 0.015);
}

TEST(PinStrength, SoftPinsGiveWayToTheDrag) {
  Session s(human(), "human48");
  ik::SolverSettings settings = s.solver_settings();
  settings.hard_pins = false;
  s.set_solver_settings(settings);
  const double drift = squat_pin_drift(s);
  std::printf("soft pins: largest foot drift %.1f mm\n", 1e3 * drift);
  EXPECT_GT(drift, 0.05);
}

}  // namespace
