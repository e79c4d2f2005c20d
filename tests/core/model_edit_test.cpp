// Tests for core/model_edit.hpp: stand_on_ground places a figure whose file puts its root at the
// world origin on the ground, floating the root of a legged figure and keeping an arm bolted.
#include "core/model_edit.hpp"

#include <gtest/gtest.h>

#include "core/bounds.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;
using fixtures::box_link;

Geometry sphere(double r) {
  Geometry g;
  g.shape = Geometry::Shape::kSphere;
  g.radius = r;
  return g;
}

// a pelvis at the origin (fixed, as a URDF root is) with one leg of two 0.45 m revolute segments
// ending in a foot sphere of radius 0.05: the lowest point is 0.95 m below the root
std::shared_ptr<const Model> legged() {
  ModelBuilder b("legged");
  LinkSpec pelvis = box_link("pelvis", "", 10, Vector3(0.1, 0.1, 0.1));
  pelvis.collision = {sphere(0.1)};
  b.add_link(pelvis);
  const char* names[] = {"thigh", "shin"};
  std::string parent = "pelvis";
  for (const char* n : names) {
    LinkSpec l = box_link(n, parent, 3, Vector3(0.05, 0.2, 0.05));
    l.joint.type = JointType::kRevolute;
    l.joint.axis = Vector3::UnitX();
    l.joint.X_PJ = Transform::from_translation(Vector3(0, parent == "pelvis" ? 0.0 : -0.45, 0));
    l.joint.limits.lower = -1;
    l.joint.limits.upper = 1;
    b.add_link(l);
    parent = n;
  }
  LinkSpec foot = box_link("foot", "shin", 1, Vector3(0.05, 0.05, 0.05));
  foot.joint.X_PJ = Transform::from_translation(Vector3(0, -0.45, 0));
  foot.collision = {sphere(0.05)};
  b.add_link(foot);
  return b.finalize();
}

// an arm 0.75 m tall bolted at its base, its base sphere reaching 0.1 m below the base
std::shared_ptr<const Model> arm() {
  ModelBuilder b("arm");
  LinkSpec base = box_link("base", "", 5, Vector3(0.1, 0.1, 0.1));
  base.collision = {sphere(0.1)};
  b.add_link(base);
  LinkSpec link = box_link("link", "base", 1, Vector3(0.05, 0.2, 0.05));
  link.joint.type = JointType::kRevolute;
  link.joint.X_PJ = Transform::from_translation(Vector3(0, 0.1, 0));
  Geometry hand = sphere(0.05);
  hand.X_LinkShape = Transform::from_translation(Vector3(0, 0.5, 0));
  link.collision = {sphere(0.05), hand};
  b.add_link(link);
  return b.finalize();
}

double lowest(const Model& m) {
  Data d(m);
  forward_kinematics(m, d, rest_configuration(m));
  return world_bounds(m, d).min.y();
}

TEST(StandOnGround, ALeggedFigureStandsOnItsFeetOnAFreeRoot) {
  const auto model = legged();
  ASSERT_NEAR(lowest(*model), -0.95, 1e-12);
  const Grounded g = stand_on_ground(model);
  EXPECT_TRUE(g.floated);
  EXPECT_NEAR(g.lift, 0.95, 1e-12);
  EXPECT_EQ(g.model->joint_type[1], JointType::kFree);
  EXPECT_NEAR(lowest(*g.model), 0.0, 1e-12);
  // the rest of the figure is as it was
  EXPECT_EQ(g.model->link_name, model->link_name);
  for (int i = 2; i < model->njoints; ++i) EXPECT_EQ(g.model->joint_type[i], model->joint_type[i]);
  EXPECT_EQ(g.model->nq, model->nq + 7);
  // placing a placed figure changes nothing
  const Grounded again = stand_on_ground(g.model);
  EXPECT_EQ(again.model, g.model);
  EXPECT_FALSE(again.floated);
}

TEST(StandOnGround, AnArmStaysBoltedAtItsBaseOnTheGround) {
  const auto model = arm();
  const Grounded g = stand_on_ground(model);
  EXPECT_FALSE(g.floated);
  EXPECT_EQ(g.model->joint_type[1], JointType::kFixed);
  EXPECT_NEAR(g.lift, 0.1, 1e-12);
  EXPECT_NEAR(lowest(*g.model), 0.0, 1e-12);
}

}  // namespace
