// Tests for sim/collision.hpp and sim/shapes.hpp: contact points against the ground plane and
// static boxes, link-against-link contacts, and the broad phase.
#include "sim/collision.hpp"

#include <gtest/gtest.h>

#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "sim/placement.hpp"
#include "sim/props.hpp"

namespace {

using core::Vector3;

struct Placed {
  std::shared_ptr<const core::Model> model;
  core::Data data;
  sim::BodyShapes shapes;
  Placed(std::shared_ptr<const core::Model> m, const Eigen::VectorXd& q)
      : model(std::move(m)),
        data(*model),
        shapes(sim::build_body_shapes(*model, core::rest_configuration(*model))) {
    if (q.size() > 0) core::forward_kinematics(*model, data, q);
  }
};

Eigen::VectorXd at(const core::Model& m, const Vector3& p, const core::Quaternion& R) {
  Eigen::VectorXd q = core::neutral_configuration(m);
  q.head<3>() = p;
  core::set_quaternion_at(q, 3, R);
  return q;
}

TEST(Collision, ABoxSunkInTheGroundTouchesItWithItsFourLowCorners) {
  sim::PropShape s;
  s.size = Vector3(0.4, 0.2, 0.6);
  Placed box(sim::make_prop("box", s, 1), Eigen::VectorXd());
  core::forward_kinematics(*box.model, box.data,
                           at(*box.model, Vector3(0, 0.099, 0), core::Quaternion::Identity()));
  std::vector<sim::ContactPoint> points;
  sim::find_environment_contacts(0, box.shapes, box.data, {}, points);
  ASSERT_EQ(points.size(), 4u);
  for (const sim::ContactPoint& p : points) {
    EXPECT_NEAR(p.depth, 0.001, 1e-12);
    EXPECT_NEAR(p.p_W.y(), -0.001, 1e-12);
    EXPECT_TRUE(p.n_W.isApprox(Vector3::UnitY()));
  }
}

// A box 1 mm above the ground touches nothing, but its four low corners are near the ground within
// 2 mm, not within 0.5 mm; sunk 1 mm, the points near the ground are its contacts.
TEST(Collision, PointsNearTheGroundAreThoseInItAndThoseJustAboveIt) {
  sim::PropShape s;
  s.size = Vector3(0.4, 0.2, 0.6);
  Placed box(sim::make_prop("box", s, 1), Eigen::VectorXd());
  const sim::GroundPlane ground;
  core::forward_kinematics(*box.model, box.data,
                           at(*box.model, Vector3(0, 0.101, 0), core::Quaternion::Identity()));
  std::vector<sim::ContactPoint> points;
  sim::find_environment_contacts(0, box.shapes, box.data, {}, points);
  EXPECT_TRUE(points.empty());
  sim::find_points_near_ground(0, box.shapes, box.data, ground, 0.002, points);
  ASSERT_EQ(points.size(), 4u);
  for (const sim::ContactPoint& p : points) {
    EXPECT_NEAR(p.depth, -0.001, 1e-12);
    EXPECT_NEAR(p.p_W.y(), 0.001, 1e-12);
  }
  points.clear();
  sim::find_points_near_ground(0, box.shapes, box.data, ground, 0.0005, points);
  EXPECT_TRUE(points.empty());

  core::forward_kinematics(*box.model, box.data,
                           at(*box.model, Vector3(0, 0.099, 0), core::Quaternion::Identity()));
  std::vector<sim::ContactPoint> contacts;
  sim::find_environment_contacts(0, box.shapes, box.data, {}, contacts);
  sim::find_points_near_ground(0, box.shapes, box.data, ground, 0.002, points);
  ASSERT_EQ(points.size(), contacts.size());
  for (size_t k = 0; k < points.size(); ++k) {
    EXPECT_EQ(points[k].p_W, contacts[k].p_W);
    EXPECT_EQ(points[k].depth, contacts[k].depth);
  }
}

TEST(Collision, ATiltedPlaneAndAStaticBoxAreSolidToo) {
  sim::Environment env;
  env.ground.normal = Vector3(0, 1, 1).normalized();
  env.boxes.push_back(
      {core::Transform::from_translation(Vector3(3, 0.5, 0)), Vector3(0.5, 0.5, 0.5)});
  auto ball = sim::make_prop("ball", {core::Geometry::Shape::kSphere, {}, 0.1, 0}, 1);
  // on the slope, 2 cm deep along its normal
  Placed a(ball, Eigen::VectorXd());
  core::forward_kinematics(*ball, a.data,
                           at(*ball, env.ground.normal * 0.08, core::Quaternion::Identity()));
  std::vector<sim::ContactPoint> points;
  sim::find_environment_contacts(0, a.shapes, a.data, env, points);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_NEAR(points[0].depth, 0.02, 1e-12);
  EXPECT_TRUE(points[0].n_W.isApprox(env.ground.normal));
  // on the box's top face, 1 cm deep, far above the slope
  core::forward_kinematics(*ball, a.data,
                           at(*ball, Vector3(3, 1.09, 2), core::Quaternion::Identity()));
  points.clear();
  env.boxes[0].pose.p.z() = 2;
  sim::find_environment_contacts(0, a.shapes, a.data, env, points);
  ASSERT_EQ(points.size(), 1u);
  EXPECT_EQ(points[0].key.env, 1);
  EXPECT_NEAR(points[0].depth, 0.01, 1e-12);
  EXPECT_TRUE(points[0].n_W.isApprox(Vector3::UnitY()));
}

TEST(Collision, ACapsuleLyingFlatRestsOnItsTwoEnds) {
  auto capsule = sim::make_prop("rod", {core::Geometry::Shape::kCapsule, {}, 0.05, 0.5}, 1);
  Placed c(capsule, Eigen::VectorXd());
  core::forward_kinematics(*capsule, c.data,
                           at(*capsule, Vector3(0, 0.049, 0), core::Quaternion::Identity()));
  std::vector<sim::ContactPoint> points;
  sim::find_environment_contacts(0, c.shapes, c.data, {}, points);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_NEAR(std::abs(points[0].p_W.z() - points[1].p_W.z()), 0.5, 1e-12);
}

TEST(Collision, AStandingFigureTouchesOnlyWithItsFeet) {
  auto m = core::build_human_figure({});
  const Eigen::VectorXd q = sim::place_on_ground(*m, core::rest_configuration(*m), {}, 1e-3);
  Placed h(m, q);
  std::vector<sim::ContactPoint> points;
  sim::find_environment_contacts(0, h.shapes, h.data, {}, points);
  ASSERT_FALSE(points.empty());
  for (const sim::ContactPoint& p : points) {
    const std::string& link = m->link_name[p.key.link];
    EXPECT_TRUE(link.find("foot") != std::string::npos || link.find("toe") != std::string::npos)
        << link;
  }
  // standing apart, no two links touch
  std::vector<int> order;
  points.clear();
  sim::find_self_contacts(0, h.shapes, h.data, order, points);
  EXPECT_TRUE(points.empty());
  // links that touch at rest (the chest and its shoulders) are never pairs
  EXPECT_LT(h.shapes.self_pairs.size(), static_cast<size_t>(m->nlinks() * (m->nlinks() - 1) / 2));
}

TEST(Collision, AnArmSwungAcrossTheBodyTouchesTheAbdomen) {
  auto m = core::build_human_figure({});
  Eigen::VectorXd q = core::rest_configuration(*m);
  // swing the right upper arm forward and across the body: the forearm meets the abdomen
  const int shoulder = m->link_index("r_uarm");
  ASSERT_GE(shoulder, 1);
  core::set_quaternion_at(q, m->idx_q[shoulder],
                          core::Quaternion(Eigen::AngleAxisd(1.0, Vector3::UnitX())) *
                              core::Quaternion(Eigen::AngleAxisd(-0.8, Vector3::UnitY())) *
                              core::Quaternion(Eigen::AngleAxisd(0.8, Vector3::UnitZ())));
  Placed h(m, q);
  std::vector<int> order;
  std::vector<sim::ContactPoint> points;
  sim::find_self_contacts(0, h.shapes, h.data, order, points);
  bool arm_touches = false;
  for (const sim::ContactPoint& p : points) {
    EXPECT_EQ(p.key.partner_body, 0);
    EXPECT_GT(p.depth, 0);
    const std::string a = m->link_name[p.key.link], b = m->link_name[p.key.partner_link];
    arm_touches = arm_touches || (a == "r_farm" && b == "abdomen");
  }
  EXPECT_TRUE(arm_touches);
}

}  // namespace
