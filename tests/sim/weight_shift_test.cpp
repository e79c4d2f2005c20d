// The dynamics-backed pin in the book's example (Yamane §9.4): human48 standing in soft contact
// with weak orientation pins on both feet, its left hand dragged down. Every step is checked:
// contacts push and never pull, the centre of pressure stays in the support polygon, and the
// root's six rows of the equation of motion are met by the contact forces alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "core/com.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "ik/solver.hpp"
#include "sim/balance.hpp"
#include "sim/placement.hpp"
#include "sim/support_polygon.hpp"
#include "sim/world.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using core::Vector3;

constexpr double kDragSeconds = 2.5;

using fixtures::human48;

Eigen::VectorXd standing_pose(const core::Model& m) {
  return sim::standing_configuration(m, core::neutral_configuration(m), {});
}

// Pelvis, hand and feet of human48 standing; the drag target moves down `depth` over 2.5 s.
struct Drag94 {
  std::shared_ptr<const core::Model> model = human48();
  Eigen::VectorXd q0 = standing_pose(*model);
  core::Data data{*model};
  int hand = model->link_index("l_hand");
  int feet[2] = {model->link_index("l_foot"), model->link_index("r_foot")};
  Vector3 hand0, pelvis0;
  double depth = 0.1;

  explicit Drag94(double d) : depth(d) {
    core::forward_kinematics(*model, data, q0);
    hand0 = data.X_W[hand].p;
    pelvis0 = data.X_W[1].p;
  }
  Vector3 target(double t) const {
    return hand0 - Vector3(0, depth * std::min(t / kDragSeconds, 1.0), 0);
  }
  Vector3 velocity(double t) const {
    return t < kDragSeconds ? Vector3(0, -depth / kDragSeconds, 0) : Vector3::Zero();
  }
  ik::LinkTask drag_task() const {
    ik::LinkTask d;
    d.role = ik::kDrag;
    d.link = hand;
    d.target_W = hand0;
    return d;
  }
  // weak orientation-only pins on the feet, as in the book
  void add_foot_pins(ik::Problem& p) const {
    for (const int foot : feet) {
      ik::LinkTask pin;
      pin.role = ik::kPin;
      pin.link = foot;
      pin.mode = ik::TaskMode::kOrientation;
      pin.target_R_W = core::Quaternion(data.X_W[foot].R);
      p.add(pin);
    }
  }
  void add_joint_references(ik::Problem& p) const { ik::add_joint_references(*model, q0, p); }
};

std::string polygon_text(const std::vector<Vector3>& polygon) {
  std::string out;
  for (const Vector3& p : polygon) {
    out += "(" + std::to_string(p.x()) + ", " + std::to_string(p.z()) + ") ";
  }
  return out;
}

// The world of the example: gravity, soft contact with friction, dynamics-backed pins.
struct DynamicDrag : Drag94 {
  sim::World world;
  int drag_id = 0;

  explicit DynamicDrag(double d, bool balance = true) : Drag94(d), world(settings()) {
    world.add_body("figure", model, q0);
    sim::Scene scene;
    scene.gravity = scene.ground_contact = scene.friction = scene.dynamic_pins = true;
    world.set_scene(scene);
    sim::BalanceSettings b;
    b.enabled = balance;
    world.set_balance_settings(b);
    ik::Problem problem;
    add_foot_pins(problem);
    add_joint_references(problem);
    drag_id = problem.add(drag_task());
    world.set_pin_problem(0, problem);
  }
  sim::WorldSettings settings() const {
    sim::WorldSettings s;
    s.contact = sim::figure_contact_settings(model->total_mass());
    return s;
  }
  void move_drag() {
    if (auto* d = world.pin_problem(0)->get<ik::LinkTask>(drag_id)) {
      d->target_W = target(world.time());
      d->velocity_W = velocity(world.time());
    }
  }
  // the drag ends; the joints keep the posture it made (their references move to it), as a
  // posing tool keeps the pose a drag leaves
  void release() {
    ik::Problem* p = world.pin_problem(0);
    p->remove(drag_id);
    const Eigen::VectorXd& q = world.body(0).q;
    for (ik::Problem::Entry& e : p->entries()) {
      if (auto* r = std::get_if<ik::JointReferenceTask>(&e.task)) {
        if (model->joint_type[r->joint] == core::JointType::kSpherical) {
          r->R_ref = core::quaternion_at(q, model->idx_q[r->joint]);
        } else {
          r->q_ref = q[model->idx_q[r->joint]];
        }
      }
    }
  }
  const Vector3& pelvis() {
    core::forward_kinematics(*model, data, world.body(0).q);
    return data.X_W[1].p;
  }
  double foot_normal_force(int foot) const {
    double f = 0;
    for (const sim::ContactPair& p : world.contact_pairs()) {
      if (p.partner_body == -1 && p.link == foot) f += p.wrench[4];
    }
    return f;
  }
  // the checks of every step; the root rows and the centre of pressure are the pins' (a fallen
  // figure has let go of them: sim/fall_response.hpp)
  void step_checked() {
    move_drag();
    world.step();
    for (const sim::ContactPair& p : world.contact_pairs()) {
      ASSERT_GE(p.wrench[4], -1e-9) << "a contact pulls at t " << world.time();
    }
    ASSERT_TRUE(world.body(0).q.allFinite() && world.body(0).v.allFinite());
    if (world.fallen(0)) return;
    ASSERT_LT(world.pin_solver(0)->report().root_residual, 1e-9) << "t " << world.time();
    core::forward_kinematics(*model, data, world.body(0).q);
    const sim::BalanceMeasures b = sim::measure_balance(world, 0, *model, data);
    if (b.cop) {
      // the polygon is drawn through the contact points on the ground; the forces act at the
      // points' depth, where friction adds a moment that shifts the CoP by up to μ_S times it
      double deepest = 0;
      for (const sim::ContactPoint& p : world.contact_points())
        deepest = std::max(deepest, p.depth);
      const double tolerance = 1e-3 + world.settings().contact.mu_static * deepest;
      ASSERT_TRUE(sim::inside_polygon(b.polygon, *b.cop, world.environment().ground, tolerance))
          << "the CoP leaves the support polygon at t " << world.time() << " (" << b.polygon.size()
          << " vertices, CoP " << b.cop->transpose() << ", polygon " << polygon_text(b.polygon)
          << ")";
    }
  }
  bool standing() {
    core::forward_kinematics(*model, data, world.body(0).q);
    return data.X_W[1].p.y() > pelvis0.y() - 0.15;
  }
};

// The velocity-level solver on the same scripted drag, feet pinned in place, 60 frames a second.
double kinematic_pelvis_shift(double depth) {
  Drag94 k(depth);
  ik::Problem problem;
  for (const int foot : k.feet) {
    ik::LinkTask pin;
    pin.role = ik::kPin;
    pin.link = foot;
    pin.mode = ik::TaskMode::kPose;
    pin.target_W = k.data.X_W[foot].p;
    pin.target_R_W = core::Quaternion(k.data.X_W[foot].R);
    problem.add(pin);
  }
  const int drag = problem.add(k.drag_task());
  ik::SolverSettings settings;
  settings.dt = 1.0 / 60;
  ik::Solver solver(*k.model, settings);
  Eigen::VectorXd q = k.q0;
  for (int frame = 1; frame <= 150; ++frame) {
    auto* d = problem.get<ik::LinkTask>(drag);
    d->target_W = k.target(frame / 60.0);
    d->velocity_W = k.velocity(frame / 60.0);
    solver.step(problem, k.data, q);
  }
  core::forward_kinematics(*k.model, k.data, q);
  return k.data.X_W[1].p.x() - k.pelvis0.x();
}

// §9.4: the hand (on +x) is pulled down; the pelvis moves the other way, clearly more than the
// kinematic solver moves it, and the figure keeps both feet on the ground.
TEST(WeightShift, PelvisMovesAwayFromThePulledHand) {
  DynamicDrag f(0.1);
  ASSERT_GT(f.hand0.x(), f.pelvis0.x()) << "the left hand is on +x";
  while (f.world.time() < kDragSeconds) {
    ASSERT_NO_FATAL_FAILURE(f.step_checked());
    ASSERT_GE(f.foot_normal_force(f.feet[0]), 0.0);
    ASSERT_GE(f.foot_normal_force(f.feet[1]), 0.0);
  }
  const double dynamic_shift = f.pelvis().x() - f.pelvis0.x();
  const double kinematic_shift = kinematic_pelvis_shift(0.1);
  std::printf("pelvis shift after 2.5 s: dynamic %.1f mm, kinematic %.1f mm\n", 1e3 * dynamic_shift,
              1e3 * kinematic_shift);
  EXPECT_LT(dynamic_shift, -0.03) << "the pelvis moves away from the hand";
  EXPECT_LT(dynamic_shift, 2 * kinematic_shift - 0.02) << "clearly more than the kinematic pelvis";
  EXPECT_TRUE(f.standing());
  EXPECT_FALSE(f.world.fallen(0));
  EXPECT_EQ(f.world.balance_state(0).supports, 2) << "both feet carry the figure";
}

// Without the balance feedback the weak foot pins hold the feet flat and nothing moves the
// centre of pressure: the same drag tips the figure over (the book: "once a figure fails to keep
// balanced, it never recovers").
TEST(WeightShift, WithoutBalanceFeedbackTheSameDragTipsTheFigure) {
  DynamicDrag f(0.1, false);
  bool fell = false;
  while (f.world.time() < 4.0 && !fell) {
    ASSERT_NO_FATAL_FAILURE(f.step_checked());
    fell = !f.standing();
  }
  EXPECT_TRUE(fell);
}

// What 9 s of a drag the figure cannot follow standing (0.3 m down in 2.5 s) did.
struct FallOutcome {
  double highest = 0;  // the centre of mass's greatest rise over its start (m)
  double deepest = 0;  // the lowest point of the figure (m, below the ground when negative)
  double work = 0;     // the work of the joints and, once fallen, the drag's spring: Σ h τ·v (J)
  double surplus = 0;  // the most energy the figure had beyond its start plus that work (J)
  bool fell = false;
  bool let_go = false;     // the world counts it fallen (its pins let go) by the end
  double joint_speed = 0;  // at the end (rad/s)
};

// Every step is checked (step_checked: contacts push, the root rows hold) along the way.
FallOutcome tipping_drag(double depth) {
  FallOutcome out;
  DynamicDrag f(depth);
  core::forward_kinematics(*f.model, f.data, f.q0);
  const double com0 = core::center_of_mass(*f.model, f.data).y();
  const double e0 = f.world.energy();
  while (f.world.time() < 9.0) {
    f.step_checked();
    if (::testing::Test::HasFatalFailure()) return out;
    const sim::Body& body = f.world.body(0);
    if (const Eigen::VectorXd* tau = f.world.driving_forces(0)) {
      out.work += f.world.settings().step * tau->dot(body.v);
    }
    out.surplus = std::max(out.surplus, f.world.energy() - e0 - out.work);
    out.deepest = std::min(out.deepest, sim::lowest_point_height(*f.model, body.q, {}));
    out.highest = std::max(out.highest, core::center_of_mass(*f.model, f.data).y() - com0);
    out.fell = out.fell || !f.standing();
  }
  out.let_go = f.world.fallen(0);
  const Eigen::VectorXd& v = f.world.body(0).v;
  out.joint_speed = v.tail(v.size() - 6).cwiseAbs().maxCoeff();
  std::printf(
      "drag %.9f m: centre of mass up to %.1f mm over its start, lowest point %.1f mm, joints' "
      "work %.0f J, energy beyond it %.3f J\n",
      depth, 1e3 * out.highest, 1e3 * out.deepest, out.work, out.surplus);
  return out;
}

// Three drags 1e-9 and 1e-6 m apart: after the fall the motion is chaotic (the joints keep
// chasing the drag and the pins from the ground), so the checks are on all three.
constexpr double kTippingDepths[] = {0.3, 0.3 + 1e-9, 0.3 - 1e-6};

// The drag makes the figure fall honestly: every step's contacts push and the root rows hold,
// joint speeds stay bounded, nothing sinks through the ground (3 cm), and the figure never has
// more energy than it started with plus the work its joints and the drag did (the contacts and
// the integrator add none: nothing explodes). Once down, its pins let go (sim/fall_response.hpp):
// joints of unbounded strength would push off the floor and heave it up (by up to 2 m before they
// did), so its centre of mass never rises far above where it stood.
TEST(WeightShift, ADragThatTipsTheFigureMakesItFallHonestly) {
  for (const double depth : kTippingDepths) {
    const FallOutcome fall = tipping_drag(depth);
    ASSERT_FALSE(HasFatalFailure()) << "drag " << depth;
    EXPECT_LT(fall.surplus, 0.5) << "energy from nowhere, drag " << depth;
    EXPECT_GT(fall.deepest, -0.03) << "sinks through the ground, drag " << depth;
    EXPECT_TRUE(fall.fell) << "the drag tips the figure, drag " << depth;
    EXPECT_TRUE(fall.let_go) << "the world knows it has fallen, drag " << depth;
    EXPECT_LT(fall.highest, 0.2) << "heaves itself up, drag " << depth;
    EXPECT_LT(fall.joint_speed, 25.0 + 1e-9) << "joint speeds bounded, drag " << depth;
  }
}

// A fallen figure stays down (the book: "it never recovers") until it is set on its feet again,
// and then its pins drive it as before.
TEST(WeightShift, AFallenFigureStandsAgainWhenItsStateIsSet) {
  DynamicDrag f(0.3);
  while (f.world.time() < 9.0 && !f.world.fallen(0)) ASSERT_NO_FATAL_FAILURE(f.step_checked());
  ASSERT_TRUE(f.world.fallen(0)) << "the 0.3 m drag tips the figure within 9 s";
  for (int k = 0; k < 200; ++k) ASSERT_NO_FATAL_FAILURE(f.step_checked());
  EXPECT_TRUE(f.world.fallen(0)) << "it stays let go";
  f.world.set_state(0, f.q0, Eigen::VectorXd::Zero(f.model->nv));
  f.release();  // the joints hold the posture it was set in
  EXPECT_FALSE(f.world.fallen(0));
  const double t0 = f.world.time();
  while (f.world.time() < t0 + 1.0) ASSERT_NO_FATAL_FAILURE(f.step_checked());
  EXPECT_FALSE(f.world.fallen(0));
  EXPECT_TRUE(f.standing());
  EXPECT_EQ(f.world.balance_state(0).supports, 2) << "both feet carry it again";
}

// Fallen, the drag is a spring of bounded force on the grabbed point: a target far above the hand
// lifts the arm but not the figure (at most a quarter of its weight pulls).
TEST(WeightShift, AFallenFigureIsPulledByTheDragWithBoundedForce) {
  DynamicDrag f(0.3);
  while (f.world.time() < 9.0 && !f.world.fallen(0)) ASSERT_NO_FATAL_FAILURE(f.step_checked());
  ASSERT_TRUE(f.world.fallen(0));
  for (int k = 0; k < 1000; ++k) ASSERT_NO_FATAL_FAILURE(f.step_checked());  // lies still
  core::forward_kinematics(*f.model, f.data, f.world.body(0).q);
  const double hand_before = f.data.X_W[f.hand].p.y();
  const double com_before = core::center_of_mass(*f.model, f.data).y();
  auto* drag = f.world.pin_problem(0)->get<ik::LinkTask>(f.drag_id);
  drag->target_W = f.data.X_W[f.hand].p + Vector3(0, 3.0, 0);
  drag->velocity_W.setZero();
  double highest_com = com_before;
  for (int k = 0; k < 2000; ++k) {
    f.world.step();
    ASSERT_TRUE(f.world.body(0).q.allFinite());
    core::forward_kinematics(*f.model, f.data, f.world.body(0).q);
    highest_com = std::max(highest_com, core::center_of_mass(*f.model, f.data).y());
  }
  const double hand_after = f.data.X_W[f.hand].p.y();
  std::printf("fallen: hand %.3f -> %.3f m, centre of mass %.3f m, highest %.3f m\n", hand_before,
              hand_after, com_before, highest_com);
  EXPECT_GT(hand_after, hand_before + 0.05) << "the pull lifts the hand";
  EXPECT_LT(highest_com, com_before + 0.15) << "a quarter of its weight cannot lift the figure";
}

// Standing with nothing dragged for 10 s, the figure gains no energy it was not given and comes
// to rest (the joints' torques could inject energy; the balance feedback must not).
TEST(WeightShift, StandingFigureGainsNoEnergy) {
  DynamicDrag f(0.0);
  f.release();
  while (f.world.time() < 1.0) ASSERT_NO_FATAL_FAILURE(f.step_checked());  // settled on its feet
  const double e0 = f.world.energy();
  double highest = e0;
  while (f.world.time() < 11.0) {
    ASSERT_NO_FATAL_FAILURE(f.step_checked());
    highest = std::max(highest, f.world.energy());
  }
  std::printf("energy after settling %.3f J, highest after %.3f J, at 10 s %.3f J\n", e0, highest,
              f.world.energy());
  EXPECT_LT(highest, e0 + 0.5);
  EXPECT_TRUE(f.standing());
  EXPECT_LT(f.world.kinetic_energy(0), 0.1);
}

// The pelvis dragged up with nothing to stand on: the joints cannot move the centre of mass, so
// the drag is out of reach; the figure falls with gravity, its joints held at their ranges.
TEST(WeightShift, PelvisLiftedWithNoContactStaysFiniteAndDamped) {
  Drag94 d(0);
  sim::World world;
  world.add_body("figure", d.model, d.q0);
  sim::Scene scene;
  scene.gravity = scene.dynamic_pins = true;
  world.set_scene(scene);
  ik::Problem problem;
  d.add_joint_references(problem);
  ik::LinkTask lift;
  lift.role = ik::kDrag;
  lift.link = 1;
  lift.target_W = d.pelvis0 + Vector3(0, 0.5, 0);
  problem.add(lift);
  world.set_pin_problem(0, problem);
  double late_speed = 0;
  for (int i = 0; i < 3000; ++i) {
    world.step();
    ASSERT_TRUE(world.body(0).q.allFinite() && world.body(0).v.allFinite()) << "step " << i;
    ASSERT_LT(world.pin_solver(0)->report().root_residual, 1e-9);
    const Eigen::VectorXd& v = world.body(0).v;
    const double joint_speed = v.tail(v.size() - 6).cwiseAbs().maxCoeff();
    ASSERT_LE(joint_speed, 25.0 + 1e-9) << "step " << i;
    if (i >= 2000) late_speed = std::max(late_speed, joint_speed);
  }
  EXPECT_LT(late_speed, 1.0) << "the joints come to rest at their ranges";
  // the centre of mass falls freely: ½ g t² in 3 s (semi-implicit Euler: g h² n(n+1)/2)
  core::forward_kinematics(*d.model, d.data, d.q0);
  const double c0 = core::center_of_mass(*d.model, d.data).y();
  core::forward_kinematics(*d.model, d.data, world.body(0).q);
  EXPECT_NEAR(core::center_of_mass(*d.model, d.data).y() - c0, -9.81e-6 * 3000 * 3001 / 2, 0.01);
}

}  // namespace
