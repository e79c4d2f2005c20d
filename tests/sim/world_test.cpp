// Tests for sim/world.hpp: the fixed-step clock, the stage pipeline chosen by the scene's effects,
// refusals that name the field, and the world as a value.
#include "sim/world.hpp"

#include <gtest/gtest.h>

#include <set>

#include "core/configuration.hpp"
#include "core/model_builder.hpp"
#include "sim/props.hpp"

namespace {

using sim::Stage;

std::shared_ptr<const core::Model> box_model() {
  sim::PropShape s;
  s.size = core::Vector3(0.2, 0.2, 0.2);
  return sim::make_prop("box", s, 1.0);
}

// a box at height y (its centre), at rest
sim::World box_world(double y) {
  sim::World w;
  auto m = box_model();
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[1] = y;
  w.add_body("box", m, q);
  return w;
}

// three capsules in a row on revolute joints about z; the last one folds back onto the first
std::shared_ptr<const core::Model> folding_chain() {
  core::ModelBuilder b("chain");
  for (int i = 0; i < 3; ++i) {
    core::LinkSpec l;
    l.name = "l" + std::to_string(i);
    l.parent = i == 0 ? "" : "l" + std::to_string(i - 1);
    l.joint.type = i == 0 ? core::JointType::kFixed : core::JointType::kRevolute;
    l.joint.axis = core::Vector3::UnitZ();
    l.joint.X_PJ = core::Transform::from_translation(core::Vector3(i == 0 ? 0 : 0.3, 0, 0));
    l.joint.limits = {-3.0, 3.0};
    l.mass = 1;
    l.com = core::Vector3(0.15, 0, 0);
    l.I_com = core::Matrix3::Identity() * 0.01;
    core::Geometry g;
    g.shape = core::Geometry::Shape::kCapsule;
    g.radius = 0.04;
    g.length = 0.2;
    g.X_LinkShape = core::Transform{Eigen::AngleAxisd(M_PI / 2, core::Vector3::UnitY()).matrix(),
                                    core::Vector3(0.15, 0, 0)};
    l.collision.push_back(g);
    b.add_link(l);
  }
  return b.finalize();
}

std::set<Stage> stages_that_ran(const sim::World& w) {
  std::set<Stage> out;
  for (int s = 0; s < sim::kStageCount; ++s) {
    if (w.counters()[static_cast<Stage>(s)] > 0) out.insert(static_cast<Stage>(s));
  }
  return out;
}

TEST(World, NoEffectsComputesNothing) {
  sim::World w = box_world(0.05);  // even penetrating the ground
  for (int k = 0; k < 1000; ++k) w.step();
  EXPECT_TRUE(stages_that_ran(w).empty());
  EXPECT_EQ(w.body(0).q[1], 0.05);
  EXPECT_NEAR(w.time(), 1.0, 1e-12);
}

TEST(World, GravityAloneRunsForwardDynamicsAndIntegration) {
  sim::World w = box_world(1.0);
  sim::Scene s;
  s.gravity = true;
  w.set_scene(s);
  for (int k = 0; k < 1000; ++k) w.step();
  EXPECT_EQ(stages_that_ran(w), (std::set<Stage>{Stage::kForwardDynamics, Stage::kIntegration}));
  EXPECT_EQ(w.counters()[Stage::kForwardDynamics], 1000u);
  EXPECT_EQ(w.counters()[Stage::kIntegration], 1000u);
}

TEST(World, GroundContactAloneRunsTheContactStagesOnlyWhileTouching) {
  sim::World w = box_world(0.099);  // 1 mm into the ground, no gravity: pushed out
  sim::Scene s;
  s.ground_contact = true;
  w.set_scene(s);
  for (int k = 0; k < 1000; ++k) w.step();
  EXPECT_EQ(stages_that_ran(w),
            (std::set<Stage>{Stage::kKinematics, Stage::kCollisionSearch, Stage::kContactForces,
                             Stage::kBiasForces, Stage::kMassMatrix, Stage::kOperationalSpace,
                             Stage::kForwardDynamics, Stage::kIntegration}));
  EXPECT_EQ(w.counters()[Stage::kCollisionSearch], 1000u);
  const auto touching = w.counters()[Stage::kContactForces];
  EXPECT_GT(touching, 0u);
  EXPECT_LT(touching, 1000u);  // it left the ground
  EXPECT_EQ(w.counters()[Stage::kMassMatrix], touching);
  EXPECT_EQ(w.counters()[Stage::kOperationalSpace], touching);
  EXPECT_GT(w.body(0).q[1], 0.1);
}

TEST(World, FrictionAloneDoesNothing) {
  sim::World w = box_world(0.099);
  sim::Scene s;
  s.friction = true;
  w.set_scene(s);
  for (int k = 0; k < 1000; ++k) w.step();
  EXPECT_TRUE(stages_that_ran(w).empty());
}

TEST(World, HardLimitsAloneProjectOnlyAndTakeTheMassMatrixOnImpact) {
  sim::World w;
  auto m = folding_chain();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(m->nv);
  v[0] = 4.0;  // toward the upper limit of 3 rad
  w.add_body("chain", m, core::neutral_configuration(*m), v);
  sim::Scene s;
  s.hard_limits = true;
  w.set_scene(s);
  for (int k = 0; k < 2000; ++k) w.step();
  EXPECT_EQ(stages_that_ran(w), (std::set<Stage>{Stage::kForwardDynamics, Stage::kLimitProjection,
                                                 Stage::kMassMatrix, Stage::kIntegration}));
  EXPECT_EQ(w.counters()[Stage::kLimitProjection], 2000u);
  EXPECT_LT(w.counters()[Stage::kMassMatrix], 2000u);
}

TEST(World, SelfCollisionAloneRunsTheContactStages) {
  sim::World w;
  auto m = folding_chain();
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[0] = 2.6;  // folded: the third capsule lies across the first
  q[1] = 2.6;
  w.add_body("chain", m, q);
  sim::Scene s;
  s.self_collision = true;
  w.set_scene(s);
  w.step();
  ASSERT_FALSE(w.contact_points().empty());
  EXPECT_EQ(w.contact_points()[0].key.partner_body, 0);
  for (int k = 0; k < 99; ++k) w.step();
  EXPECT_EQ(stages_that_ran(w),
            (std::set<Stage>{Stage::kKinematics, Stage::kCollisionSearch, Stage::kContactForces,
                             Stage::kBiasForces, Stage::kMassMatrix, Stage::kOperationalSpace,
                             Stage::kForwardDynamics, Stage::kIntegration}));
}

TEST(World, SimulatedTimeFollowsTheSummedWallTimeAtAnyCallRate) {
  for (const double rate : {30.0, 60.0, 500.0, 47.3}) {
    sim::World w = box_world(1.0);
    sim::Scene s;
    s.gravity = true;
    w.set_scene(s);
    double summed = 0;
    for (int k = 0; k < static_cast<int>(10 * rate); ++k) {
      w.advance(1.0 / rate);
      summed += 1.0 / rate;
      ASSERT_LE(std::abs(w.time() - summed), w.settings().step + 1e-12) << rate;
    }
  }
}

TEST(World, IsAValueThatCopiesAndRestores) {
  sim::World w = box_world(0.3);
  sim::Scene s;
  s.gravity = s.ground_contact = s.friction = true;
  w.set_scene(s);
  for (int k = 0; k < 300; ++k) w.step();  // landed
  const sim::World saved = w;
  for (int k = 0; k < 500; ++k) w.step();
  sim::World restored = saved;
  for (int k = 0; k < 500; ++k) restored.step();
  EXPECT_EQ(restored.body(0).q, w.body(0).q);  // deterministic, bit for bit
  EXPECT_EQ(restored.body(0).v, w.body(0).v);
  EXPECT_EQ(restored.time(), w.time());
}

TEST(World, RefusesBadInputNamingTheField) {
  auto expect_error = [](auto&& f, const std::string& field) {
    try {
      f();
      ADD_FAILURE() << "no error for " << field;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  sim::WorldSettings bad_step;
  bad_step.step = -1e-3;
  expect_error([&] { sim::World w(bad_step); }, "step");
  sim::WorldSettings nan_kp;
  nan_kp.contact.kp = std::nan("");
  expect_error([&] { sim::World w(nan_kp); }, "contact.kp");
  sim::Environment tilted;
  tilted.ground.normal = core::Vector3(0, 2, 0);
  expect_error([&] { sim::World w({}, tilted); }, "ground.normal");
  expect_error([] { sim::make_prop("crate", {}, -1.0); }, "mass");
  expect_error([] { sim::Scene::from_names({"gravity", "wind"}); }, "wind");
  sim::World w;
  auto m = box_model();
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[0] = std::nan("");
  expect_error([&] { w.add_body("box", m, q); }, "box");
  expect_error([&] { w.advance(-1); }, "dt");
}

}  // namespace
