// Tests of the dynamic_pins effect (sim/world_pins.cpp): bodies whose joints are driven by the
// acceleration-level solver while their root is moved by gravity and the contact forces alone
// (Yamane ch. 9).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "core/com.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "sim/placement.hpp"
#include "sim/props.hpp"
#include "sim/world.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using core::Vector3;

sim::Scene standing_scene() {
  sim::Scene scene;
  scene.gravity = scene.ground_contact = scene.friction = scene.dynamic_pins = true;
  return scene;
}

// A box with an empty problem has no joint to drive: the dynamics-backed path must move its root
// exactly as the passive path does (the explicit contact forces of the step's start are the
// semi-implicit integrator's).
TEST(DynamicPins, BoxWithNoTasksMovesLikeAPassiveBox) {
  Eigen::VectorXd ends[2];
  for (const bool pinned : {false, true}) {
    sim::WorldSettings settings;
    settings.integrator = sim::Integrator::kSemiImplicit;
    sim::World w(settings);
    sim::PropShape shape;
    shape.size = Vector3(0.2, 0.1, 0.4);
    auto m = sim::make_prop("box", shape, 5.0);
    Eigen::VectorXd q = core::neutral_configuration(*m);
    q[1] = 0.06;
    core::set_quaternion_at(q, 3, core::Quaternion(Eigen::AngleAxisd(0.2, Vector3::UnitX())));
    Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
    v[3] = 0.5;  // sliding and tumbling onto its face
    w.add_body("box", m, q, v);
    w.set_scene(standing_scene());
    if (pinned) w.set_pin_problem(0, ik::Problem{});
    for (int i = 0; i < 1000; ++i) w.step();
    ends[pinned] = w.body(0).q;
  }
  EXPECT_LT((ends[0] - ends[1]).norm(), 1e-9);
}

// A foot (box, free root) carrying a heavy upright body on an ankle: a fixed joint, or a revolute
// joint held rigid by the solver with no task (q̈ = 0).
std::shared_ptr<const core::Model> foot_and_body(bool revolute) {
  core::ModelBuilder b("statue");
  core::LinkSpec foot;
  foot.name = "foot";
  foot.joint.type = core::JointType::kFree;
  foot.mass = 1;
  foot.I_com = core::Matrix3::Identity() * 0.005;
  core::Geometry g;
  g.shape = core::Geometry::Shape::kBox;
  g.size = Vector3(0.1, 0.05, 0.25);
  foot.collision.push_back(g);
  b.add_link(foot);
  core::LinkSpec body;
  body.name = "body";
  body.parent = "foot";
  body.joint.type = revolute ? core::JointType::kRevolute : core::JointType::kFixed;
  body.joint.axis = Vector3::UnitX();
  body.joint.limits = {-1, 1};
  body.joint.X_PJ = core::Transform::from_translation(Vector3(0, 0.05, -0.05));
  body.mass = 60;
  body.com = Vector3(0, 0.8, 0.06);
  body.I_com = Vector3(6, 1, 6).asDiagonal();
  b.add_link(body);
  return b.finalize();
}

// The contact forces reach the root through Q = Σ Jᵀ f over a joint: a rigidly held revolute
// ankle gives the motion of a welded one.
TEST(DynamicPins, RigidlyHeldJointMovesLikeAFixedOne) {
  Eigen::VectorXd ends[2];
  for (const bool revolute : {false, true}) {
    sim::WorldSettings settings;
    settings.integrator = sim::Integrator::kSemiImplicit;
    settings.contact = sim::figure_contact_settings(61);
    sim::World w(settings);
    auto m = foot_and_body(revolute);
    Eigen::VectorXd q = core::neutral_configuration(*m);
    q[1] = 0.03;  // dropped from 5 mm
    w.add_body("statue", m, q);
    w.set_scene(standing_scene());
    if (revolute) w.set_pin_problem(0, ik::Problem{});
    for (int i = 0; i < 2000; ++i) w.step();
    ends[revolute] = w.body(0).q.head<7>();
  }
  EXPECT_LT((ends[0] - ends[1]).norm(), 1e-9);
}

using fixtures::human48;

// human48 standing (sim::standing_configuration) in soft contact, its joints driven by the
// dynamics-backed solver
struct StandingFigure {
  std::shared_ptr<const core::Model> model = human48();
  sim::World world{settings(model->total_mass())};
  Eigen::VectorXd q0;
  core::Data data{*model};

  static sim::WorldSettings settings(double mass) {
    sim::WorldSettings s;
    s.contact = sim::figure_contact_settings(mass);
    return s;
  }
  StandingFigure() {
    q0 = sim::standing_configuration(*model, core::neutral_configuration(*model), {});
    world.add_body("figure", model, q0);
    world.set_scene(standing_scene());
  }
  Vector3 com() {
    core::forward_kinematics(*model, data, world.body(0).q);
    return core::center_of_mass(*model, data);
  }
  // every joint pulled toward its standing value
  void add_joint_references(ik::Problem& problem) const {
    ik::add_joint_references(*model, q0, problem);
  }
  // checks of every step: no hidden force on the root, contacts push and never pull
  void step_and_check(int steps, double max_com_shift) {
    const Vector3 c0 = com();
    for (int i = 0; i < steps; ++i) {
      world.step();
      ASSERT_LT(world.pin_solver(0)->report().root_residual, 1e-9) << "step " << i;
      for (const sim::ContactPair& p : world.contact_pairs()) {
        ASSERT_GE(p.wrench[4], -1e-9) << "a contact pulls at step " << i;
      }
      const Vector3 shift = com() - c0;
      ASSERT_LT(std::hypot(shift.x(), shift.z()), max_com_shift) << "step " << i;
      ASSERT_LT(std::abs(shift.y()), 0.005) << "step " << i;
    }
  }
};

TEST(DynamicPins, FigureHeldRigidStaysStanding) {
  StandingFigure f;
  f.world.set_pin_problem(0, ik::Problem{});
  f.step_and_check(2000, 0.01);
}

TEST(DynamicPins, FigureHeldByJointReferencesStaysStanding) {
  StandingFigure f;
  ik::Problem problem;
  f.add_joint_references(problem);
  f.world.set_pin_problem(0, problem);
  f.step_and_check(3000, 0.015);
}

TEST(DynamicPins, OffMeansTheProblemIsIgnored) {
  sim::Scene scene = standing_scene();
  scene.dynamic_pins = false;
  StandingFigure with, without;
  ik::Problem problem;
  with.add_joint_references(problem);
  with.world.set_pin_problem(0, problem);
  for (StandingFigure* f : {&with, &without}) {
    f->world.set_scene(scene);
    for (int i = 0; i < 200; ++i) f->world.step();
  }
  EXPECT_EQ(with.world.body(0).q, without.world.body(0).q);
  EXPECT_EQ(
      with.world.pin_solver(0)->report().top_rows + with.world.pin_solver(0)->report().lower_rows,
      0)
      << "the solver never ran";
}

}  // namespace
