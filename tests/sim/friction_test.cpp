// The soft-contact friction of sim/soft_contact.hpp on the book's box tests (Yamane §6.4.1,
// Figs. 6.3–6.4; reference/digest-check.md "Y ch.6 soft contact", tests 1, 2 and 7).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tests/sim/sim_fixtures.hpp"

namespace {

using sim_fixtures::BoxOnGround;

struct Stop {
  double distance = -1;  // m travelled until the speed falls below 1 mm/s
  double time = -1;      // s
};

Stop slide_until_stop(double v0, double mu_s, double mu_d, double kfp, double kfd) {
  sim::WorldSettings s;
  s.contact.kp = 1e5;
  s.contact.kd = 1e3;
  s.contact.mu_static = mu_s;
  s.contact.mu_dynamic = mu_d;
  s.contact.kfp = kfp;
  s.contact.kfd = kfd;
  BoxOnGround box(s, v0);
  const double x0 = box.distance();
  for (int k = 0; k < 3000; ++k) {
    box.world.step();
    if (std::abs(box.speed()) < 1e-3) return {box.distance() - x0, box.world.time()};
  }
  return {};
}

struct SlideCase {
  double v0, mu_s, mu_d;
};

// Coulomb: d = v0² / (2 μD g), t = v0 / (μD g) with g = 9.81
TEST(Friction, BoxSlidingOnAFloorStopsWhereCoulombSays) {
  const SlideCase cases[] = {{1, 0.35, 0.25}, {2, 0.35, 0.25}, {1, 0.65, 0.55}, {2, 0.65, 0.55}};
  for (const SlideCase& c : cases) {
    const double d = c.v0 * c.v0 / (2 * c.mu_d * 9.81), t = c.v0 / (c.mu_d * 9.81);
    const Stop soft = slide_until_stop(c.v0, c.mu_s, c.mu_d, 1000, 700);
    const Stop stiff = slide_until_stop(c.v0, c.mu_s, c.mu_d, 2000, 1400);
    std::printf(
        "v0 %.0f, (%.2f, %.2f): Coulomb %.3f m / %.3f s; (1000, 700) %.4f m / %.3f s; "
        "(2000, 1400) %.4f m / %.3f s\n",
        c.v0, c.mu_s, c.mu_d, d, t, soft.distance, soft.time, stiff.distance, stiff.time);
    for (const Stop& s : {soft, stiff}) {
      EXPECT_NEAR(s.distance, d, 0.03 * d);
      EXPECT_NEAR(s.time, t, 0.03 * t);
    }
    // the book: insensitive to the choice between the two friction gain sets
    EXPECT_NEAR(soft.distance, stiff.distance, 0.005 * d);
    EXPECT_NEAR(soft.time, stiff.time, 0.01 * t);
  }
}

// down-slope acceleration g (sin 30° − μD cos 30°), measured between 0.2 s and 0.5 s
double slope_acceleration(BoxOnGround& box) {
  for (int k = 0; k < 200; ++k) box.world.step();
  const double v1 = box.speed();
  for (int k = 0; k < 300; ++k) box.world.step();
  return (box.speed() - v1) / 0.3;
}

sim::WorldSettings slope_settings(double mu_s, double mu_d) {
  sim::WorldSettings s;
  s.contact.mu_static = mu_s;
  s.contact.mu_dynamic = mu_d;
  s.contact.kfp = 2000;
  s.contact.kfd = 1400;
  return s;
}

TEST(Friction, SlopeBelowTheFrictionAngleAccelerates) {
  const double slope = M_PI / 6;
  BoxOnGround box(slope_settings(0.64, 0.54), 1.0, slope);
  const double expected = 9.81 * (std::sin(slope) - 0.54 * std::cos(slope));  // +0.317
  const double a = slope_acceleration(box);
  std::printf("(0.64, 0.54) on 30°: %.4f m/s² (Coulomb %.4f)\n", a, expected);
  EXPECT_NEAR(a, expected, 0.02 * std::abs(expected));
}

TEST(Friction, SlopeAboveTheFrictionAngleStopsThenStaticFrictionHolds) {
  const double slope = M_PI / 6;
  BoxOnGround box(slope_settings(0.72, 0.62), 1.0, slope);
  const double x0 = box.distance();
  const double expected = 9.81 * (std::sin(slope) - 0.62 * std::cos(slope));  // −0.362
  const double a = slope_acceleration(box);
  EXPECT_NEAR(a, expected, 0.02 * std::abs(expected));
  // it stops where Coulomb says, from 1 m/s: d = 1 / (2 |a|)
  for (int k = 0; k < 5000; ++k) box.world.step();
  // stuck: the anchor spring and damper settle the last millimetres (time constant kFD / kFP)
  EXPECT_LT(std::abs(box.speed()), 1e-3);
  for (const sim::ContactPair& p : box.world.contact_pairs()) EXPECT_TRUE(p.sticking);
  const double stop = box.distance() - x0;
  std::printf("(0.72, 0.62) on 30°: %.4f m/s², stopped after %.4f m (Coulomb %.4f m)\n", a, stop,
              1.0 / (2 * std::abs(expected)));
  EXPECT_NEAR(stop, 1.0 / (2 * std::abs(expected)), 0.01);
  // static friction holds it: over 10 s more the box creeps less than the anchor spring's
  // largest stretch μS f_z / kFP allows, and settles
  const double held = box.distance();
  for (int k = 0; k < 10000; ++k) box.world.step();
  const double bound = 0.72 * 9.81 * std::cos(slope) / 2000;
  std::printf("drift over 10 s held: %.2e m (anchor bound %.2e m)\n", box.distance() - held, bound);
  EXPECT_LT(std::abs(box.distance() - held), bound);
  EXPECT_LT(std::abs(box.speed()), 1e-6);
}

TEST(Friction, FrictionOffLetsTheBoxSlideForever) {
  sim::WorldSettings s;
  BoxOnGround box(s, 1.0);
  sim::Scene scene = box.world.scene();
  scene.friction = false;
  box.world.set_scene(scene);
  for (int k = 0; k < 1000; ++k) box.world.step();
  EXPECT_NEAR(box.speed(), 1.0, 1e-6);
}

}  // namespace
