// Tests of a session's physics (animator/physics_session.hpp, animator/session_physics.cpp): the
// "Stand" effects keep human48 standing, a drag of the left hand moves the pelvis away from it,
// switching the effects off returns to kinematic posing without a jump, and nothing is simulated
// while the effects are off.
#include <gtest/gtest.h>

#include <cmath>

#include "animator_fixtures.hpp"
#include "sim/support_polygon.hpp"

namespace {

using animator::Session;
using animator_test::human;
using animator_test::position;
using animator_test::run;
using core::Vector3;

constexpr double kFrame = 1.0 / 60;

sim::Scene stand() {
  sim::Scene s;
  s.gravity = s.ground_contact = s.friction = s.dynamic_pins = true;
  return s;
}

double max_abs_difference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(PhysicsSession, StandKeepsTheFigureStandingForTwoSeconds) {
  Session s(human(), "human48");
  s.set_scene(stand());
  ASSERT_NE(s.physics(), nullptr);
  EXPECT_TRUE(s.needs_tick());
  const double pelvis0 = position(s, "pelvis").y();
  for (int k = 0; k < 120; ++k) {
    s.tick(kFrame);
    ASSERT_NEAR(position(s, "pelvis").y(), pelvis0, 0.02) << "tick " << k;
  }
  const animator::PhysicsMeasures m = s.physics()->measures();
  EXPECT_TRUE(m.balanced);
  ASSERT_TRUE(m.cop.has_value());
  EXPECT_GE(m.support_polygon.size(), 3u);
  double weight = 0;
  for (const animator::ContactArrow& c : m.contacts) weight += c.force.y();
  EXPECT_NEAR(weight, s.model().total_mass() * 9.81, 0.1 * s.model().total_mass() * 9.81);
  // each effect that runs costs something, one that is off nothing
  EXPECT_GT(m.effect_us[static_cast<int>(sim::Effect::kDynamicPins)], 0);
  EXPECT_GT(m.effect_us[static_cast<int>(sim::Effect::kGroundContact)], 0);
  EXPECT_EQ(m.effect_us[static_cast<int>(sim::Effect::kSelfCollision)], 0);
  EXPECT_GT(m.total_us, 0);
}

// The left hand is on the figure's +x side (it faces +z): pulled down, it drags the upper body
// toward it, and the pelvis moves the other way to keep the centre of mass over the feet.
TEST(PhysicsSession, DraggingTheLeftHandDownMovesThePelvisAwayFromIt) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 30, kFrame);
  const int hand = s.model().link_index("l_hand");
  const Vector3 hand0 = position(s, "l_hand");
  const Vector3 pelvis0 = position(s, "pelvis");
  ASSERT_GT(hand0.x(), pelvis0.x()) << "the left hand is not on the +x side";
  s.drag_begin(hand, hand0);
  for (int k = 1; k <= 30; ++k) {
    s.drag_move(hand0 - Vector3(0, 0.12 * k / 30, 0));
    s.tick(kFrame);
  }
  run(s, 30, kFrame);
  const Vector3 hand1 = position(s, "l_hand");
  const Vector3 pelvis1 = position(s, "pelvis");
  const animator::PhysicsMeasures m = s.physics()->measures();
  s.drag_end();
  EXPECT_LT(hand1.y(), hand0.y() - 0.05) << "the hand did not follow the drag down";
  EXPECT_LT(pelvis1.x(), pelvis0.x() - 0.02) << "the pelvis did not move away from the hand";
  EXPECT_NEAR(pelvis1.y(), pelvis0.y(), 0.03) << "the figure did not stay up";
  ASSERT_TRUE(m.cop.has_value()) << "the feet left the ground";
  EXPECT_TRUE(sim::inside_polygon(m.support_polygon, *m.cop, {}, 0.01));
  EXPECT_TRUE(s.history().can_undo());
  EXPECT_EQ(s.history().undo_labels().back(), "drag");
}

// Stand pins the feet it stands on by their orientation and the balance feedback keeps the
// figure over them: a slow drag of the hand, held and let go, leaves it standing and balanced in
// the posture the drag made.
TEST(PhysicsSession, AfterADragTheFigureStaysBalancedInItsNewPosture) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 30, kFrame);
  ASSERT_EQ(s.physics()->world().balance_state(0).supports, 2) << "both feet are supports";
  const int hand = s.model().link_index("l_hand");
  const Vector3 hand0 = position(s, "l_hand");
  const double pelvis_height = position(s, "pelvis").y();
  s.drag_begin(hand, hand0);
  for (int k = 1; k <= 120; ++k) {
    s.drag_move(hand0 - Vector3(0, 0.08 * k / 120, 0));
    s.tick(kFrame);
  }
  s.drag_end();
  const double hand_height = position(s, "l_hand").y();
  for (int k = 0; k < 240; ++k) {
    s.tick(kFrame);
    ASSERT_NEAR(position(s, "pelvis").y(), pelvis_height, 0.05) << "tick " << k;
  }
  EXPECT_TRUE(s.physics()->measures().balanced);
  EXPECT_NEAR(position(s, "l_hand").y(), hand_height, 0.03) << "the posture is kept";
  EXPECT_LT(s.physics()->world().kinetic_energy(0), 0.5) << "at rest";
}

// A drag the figure cannot follow standing tips it over: the measures say it has fallen (its pins
// let go: sim/fall_response.hpp), and undoing the drag stands it up again where it was.
TEST(PhysicsSession, AFallenFigureIsReportedAndUndoStandsItUp) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 30, kFrame);
  const int hand = s.model().link_index("l_hand");
  const Vector3 hand0 = position(s, "l_hand");
  const Vector3 pelvis0 = position(s, "pelvis");
  EXPECT_FALSE(s.physics()->measures().fallen);
  s.drag_begin(hand, hand0);
  bool fallen = false;
  for (int k = 1; k <= 360 && !fallen; ++k) {
    s.drag_move(hand0 - Vector3(0, 0.6 * std::min(k / 30.0, 1.0), 0));
    s.tick(kFrame);
    fallen = s.physics()->measures().fallen;
  }
  s.drag_end();
  ASSERT_TRUE(fallen) << "a 0.6 m drag in 0.5 s tips the figure within 6 s";
  EXPECT_LT(position(s, "pelvis").y(), pelvis0.y() - 0.3) << "it is down";
  run(s, 60, kFrame);
  EXPECT_TRUE(s.physics()->measures().fallen) << "it stays down";
  ASSERT_TRUE(s.undo());
  EXPECT_NEAR(position(s, "pelvis").y(), pelvis0.y(), 0.02) << "undo stands it up";
  for (int k = 0; k < 60; ++k) {
    s.tick(kFrame);
    ASSERT_FALSE(s.physics()->measures().fallen) << "tick " << k;
  }
  EXPECT_NEAR(position(s, "pelvis").y(), pelvis0.y(), 0.03) << "and it keeps standing";
}

TEST(PhysicsSession, EffectsOffReturnToKinematicPosingWithoutAJump) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 10, kFrame);
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);  // where physics holds it now
  run(s, 10, kFrame);
  const Eigen::VectorXd q = s.q();
  s.set_scene(sim::Scene{});
  EXPECT_EQ(s.physics(), nullptr);
  EXPECT_EQ(max_abs_difference(s.q(), q), 0);
  EXPECT_FALSE(s.needs_tick());
  run(s, 10, kFrame);
  EXPECT_EQ(max_abs_difference(s.q(), q), 0) << "the pose moved after the switch";
  // a kinematic drag works from there
  const int hand = s.model().link_index("r_hand");
  const Vector3 hand0 = position(s, "r_hand");
  s.drag_begin(hand, hand0);
  s.drag_move(hand0 + Vector3(0, 0.1, 0));
  run(s, 30, kFrame);
  s.drag_end();
  EXPECT_NEAR(position(s, "r_hand").y(), hand0.y() + 0.1, 0.01);
  // undo takes the drag back, then the effects come back on at the pose they left
  ASSERT_TRUE(s.undo());
  EXPECT_EQ(s.history().undo_labels().back(), "scene effects");
  EXPECT_LT(max_abs_difference(s.q(), q), 1e-12);
  ASSERT_TRUE(s.undo());
  EXPECT_NE(s.physics(), nullptr);
}

TEST(PhysicsSession, NothingIsSimulatedWithTheEffectsOff) {
  Session s(human(), "human48");
  const Eigen::VectorXd q = s.q();
  sim::Scene friction_only;
  friction_only.friction = true;
  s.set_scene(friction_only);
  EXPECT_EQ(s.physics(), nullptr);
  EXPECT_FALSE(s.needs_tick());
  run(s, 30, kFrame);
  EXPECT_EQ(s.q(), q);
}

TEST(PhysicsSession, KeysInsertedWhilePhysicsRunsKeyThePoseShown) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 10, kFrame);
  const Eigen::VectorXd shown = s.q();
  const int k = s.key_insert(0.0);
  Eigen::VectorXd keyed(shown.size());
  s.keys().sample(s.model(), 0.0, keyed);
  EXPECT_LT(max_abs_difference(keyed, shown), 1e-9);
  EXPECT_EQ(k, 0);
}

// The page's gesture (tests/web/physics_stand_test.mjs): the left hand pulled 12 cm down in ten
// samples 50 ms apart, held two seconds, let go. Standing in the posture it leaves, the figure
// bears little weight on its left foot, which rises out of the soft ground by a fraction of a
// millimetre now and then; it stays balanced on every frame of the two seconds after (the page
// shows "Balance lost" on any frame that is not).
TEST(PhysicsSession, AFootUnloadedForAMomentIsStillStandingOnTheGround) {
  Session s(human(), "human48");
  s.set_scene(stand());
  run(s, 48, kFrame);
  const int hand = s.model().link_index("l_hand");
  const Vector3 hand0 = position(s, "l_hand");
  s.drag_begin(hand, hand0);
  for (int k = 0; k < 30; ++k) {
    s.drag_move(hand0 - Vector3(0, 0.12 * std::min(10, 1 + k / 3) / 10, 0));
    s.tick(kFrame);
  }
  run(s, 120, kFrame);
  s.drag_end();
  for (int k = 0; k < 120; ++k) {
    s.tick(kFrame);
    const animator::PhysicsMeasures m = s.physics()->measures();
    ASSERT_TRUE(m.balanced) << "tick " << k
                            << " after the drag was let go: the support polygon has "
                            << m.support_polygon.size() << " vertices";
    ASSERT_GE(m.support_polygon.size(), 3u) << "tick " << k;
  }
}

}  // namespace
