// Tests for core/model_edit.hpp: stand_on_ground places a figure whose file puts its root at the
// world origin on the ground, floating the root of a legged figure and keeping an arm bolted;
// stand_motion_on_ground places an imported figure and its clip so that the lowest point it
// reaches (its mesh's, when it has one) is on the ground.
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
std::shared_ptr<const Model> legged(JointType root = JointType::kFixed) {
  ModelBuilder b("legged");
  LinkSpec pelvis = box_link("pelvis", "", 10, Vector3(0.1, 0.1, 0.1));
  pelvis.joint.type = root;
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

// the lowest point of the figure's shapes in configuration q
double lowest_at(const Model& m, const Eigen::VectorXd& q) {
  Data d(m);
  forward_kinematics(m, d, q);
  return world_bounds(m, d).min.y();
}

// the legged figure on a free root, its pelvis at `height`, the hip bent by `hip` (rad)
Eigen::VectorXd pose(const Model& m, double height, double hip) {
  Eigen::VectorXd q = neutral_configuration(m);
  q[1] = height;
  q[m.idx_q[m.link_index("thigh")]] = hip;
  return q;
}

TEST(StandMotionOnGround, AClipStandsOnTheLowestPointItReaches) {
  const auto model = legged(JointType::kFree);
  // the pelvis 0.3 m up with the leg hanging (foot 0.65 m under the floor), then the leg swung
  // forward and the pelvis higher: the first frame is the lowest, at -0.65 m
  const std::vector<Eigen::VectorXd> frames = {pose(*model, 0.3, 0.0), pose(*model, 0.5, 0.8),
                                               pose(*model, 0.4, -0.5)};
  ASSERT_NEAR(lowest_at(*model, frames[0]), -0.65, 1e-12);
  const Grounded g = stand_motion_on_ground(model, frames, nullptr);
  EXPECT_NEAR(g.lift, 0.65, 1e-12);
  EXPECT_FALSE(g.floated);
  double lowest_after = kInfinity;
  for (const Eigen::VectorXd& q : frames) {
    // every link moved straight up by the lift, the same joint coordinates
    Data before(*model), after(*g.model);
    forward_kinematics(*model, before, q);
    forward_kinematics(*g.model, after, q);
    for (int i = 1; i < model->njoints; ++i) {
      EXPECT_LT((after.X_W[i].p - before.X_W[i].p - Vector3(0, 0.65, 0)).norm(), 1e-12);
      EXPECT_LT((after.X_W[i].R - before.X_W[i].R).norm(), 1e-15);
    }
    lowest_after = std::min(lowest_after, lowest_at(*g.model, q));
  }
  EXPECT_NEAR(lowest_after, 0.0, 1e-12);
  // a placed motion placed again is itself
  EXPECT_EQ(stand_motion_on_ground(g.model, frames, nullptr).model, g.model);
  // a figure floating above the ground comes down as well; with no frames, its rest pose
  const std::vector<Eigen::VectorXd> high = {pose(*model, 2.0, 0.0)};
  EXPECT_NEAR(stand_motion_on_ground(model, high, nullptr).lift, -1.05, 1e-12);
  EXPECT_NEAR(stand_motion_on_ground(model, {}, nullptr).lift, 0.95, 1e-12);
}

TEST(StandMotionOnGround, ASkinnedFigureStandsOnItsMeshNotOnItsLinks) {
  const auto model = legged(JointType::kFree);
  const std::vector<Eigen::VectorXd> frames = {pose(*model, 1.0, 0.0), pose(*model, 1.2, 0.3)};
  // one vertex of a boot 0.15 m under the foot's origin (0.1 m below its sphere), on the foot,
  // and one on the pelvis; bound at the first frame
  Data bind(*model);
  forward_kinematics(*model, bind, frames[0]);
  const int foot = model->link_index("foot"), pelvis = model->link_index("pelvis");
  SkinnedMesh skin;
  skin.bones = {foot, pelvis};
  skin.inverse_bind = {bind.X_W[foot].inverse(), bind.X_W[pelvis].inverse()};
  skin.positions = {(bind.X_W[foot].p - Vector3(0, 0.15, 0)).cast<float>(),
                    bind.X_W[pelvis].p.cast<float>()};
  skin.joints = {{0, 0, 0, 0}, {1, 0, 0, 0}};
  skin.weights = {{1, 0, 0, 0}, {1, 0, 0, 0}};
  // the boot's lowest point over the clip: the foot is lowest in the first frame, at 1 - 0.9 m;
  // the boot reaches 0.15 m below that (the foot sphere alone: 0.05 m)
  const Grounded g = stand_motion_on_ground(model, frames, &skin);
  EXPECT_NEAR(g.lift, -(0.1 - 0.15), 1e-6);  // float vertices
  EXPECT_NEAR(stand_motion_on_ground(model, frames, nullptr).lift, -(0.1 - 0.05), 1e-12);
  // an empty mesh measures the links
  const SkinnedMesh no_mesh;
  EXPECT_NEAR(stand_motion_on_ground(model, frames, &no_mesh).lift, -0.05, 1e-12);
}

}  // namespace
