// The integrators of sim::World on the book's falling box (Yamane §6.4.2, Fig. 6.5) and on the
// invariants every integrator must keep: free fall, no energy from nowhere, a resting box whose
// weight is carried whatever its number of contact points.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/configuration.hpp"
#include "sim/props.hpp"
#include "sim/world.hpp"

namespace {

using sim::Integrator;

struct Fall {
  bool finite = true;
  double max_depth = 0;  // deepest penetration (m)
  double max_gain = 0;   // largest energy above the start (J)
  core::Vector3 final_position = core::Vector3::Zero();
  double final_tilt = 0;  // angle between the vertical and the nearest box axis (rad)
  double final_speed = 0;
  double pull = 0;  // the most any contact pair pulled along its normal (N)
};

// a 1 kg 0.2 × 0.1 × 0.3 m box dropped tilted from 0.5 m while moving sideways, 3 s
Fall drop_box(Integrator integrator, double h) {
  sim::WorldSettings s;
  s.step = h;
  s.integrator = integrator;
  sim::World w(s);
  sim::PropShape shape;
  shape.size = core::Vector3(0.2, 0.1, 0.3);
  auto m = sim::make_prop("box", shape, 1.0);
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[1] = 0.5;
  core::set_quaternion_at(
      q, 3, core::Quaternion(Eigen::AngleAxisd(0.4, core::Vector3(1, 0.3, 0.2).normalized())));
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  v[3] = 0.5;
  w.add_body("box", m, q, v);
  sim::Scene scene;
  scene.gravity = scene.ground_contact = scene.friction = true;
  w.set_scene(scene);
  Fall f;
  const double e0 = w.energy();
  const int steps = static_cast<int>(std::round(3.0 / h));
  for (int k = 0; k < steps; ++k) {
    w.step();
    if (!w.body(0).q.allFinite() || !w.body(0).v.allFinite()) {
      f.finite = false;
      return f;
    }
    for (const sim::ContactPoint& p : w.contact_points())
      f.max_depth = std::max(f.max_depth, p.depth);
    for (const sim::ContactPair& p : w.contact_pairs())
      f.pull = std::max(f.pull, -p.wrench.tail<3>().dot(p.normal_W));
    f.max_gain = std::max(f.max_gain, w.energy() - e0);
  }
  f.final_position = w.body(0).q.head<3>();
  const core::Matrix3 R = core::quaternion_at(w.body(0).q, 3).toRotationMatrix();
  f.final_tilt = std::acos(std::min(1.0, R.row(1).cwiseAbs().maxCoeff()));
  f.final_speed = w.body(0).v.norm();
  return f;
}

// correct: finite, never deeper than 1 cm, never with more energy than it started with, at rest
// lying flat on a face, within 3 cm of where a fine-step reference lands (the bounces of a
// tilted box landing on a corner scatter the landing spot by millimetres between step sizes;
// an integrator gone wrong is decimetres to metres off, or flies away)
bool correct(const Fall& f, const Fall& reference) {
  return f.finite && f.max_depth < 1e-2 && f.max_gain < 1e-3 && f.final_speed < 1e-3 &&
         f.final_tilt < 1e-2 && (f.final_position - reference.final_position).norm() < 3e-2;
}

// The linearized implicit step asks a pair that is coming apart fast to pull; the solve lets such
// a pair go instead (sim/contact_dynamics.hpp): over the bounces of the dropped box at every step
// size, no pair ever pulls.
TEST(Integrators, ImplicitContactsOnlyPush) {
  for (const double h : {2.5e-4, 1e-3, 4e-3, 8e-3}) {
    const Fall f = drop_box(Integrator::kImplicit, h);
    ASSERT_TRUE(f.finite) << "h " << h;
    EXPECT_LE(f.pull, 1e-9) << "h " << h;
  }
}

TEST(Integrators, ImplicitTakesStepsExplicitIntegratorsCannot) {
  const Fall reference = drop_box(Integrator::kRk4, 5e-5);
  ASSERT_TRUE(reference.finite);
  const double steps[] = {1e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8e-3};
  double largest[3] = {0, 0, 0};
  for (const Integrator in : {Integrator::kImplicit, Integrator::kSemiImplicit, Integrator::kRk4}) {
    for (const double h : steps) {
      const Fall f = drop_box(in, h);
      const bool ok = correct(f, reference);
      std::printf("%-13s h = %6.2f ms: %s (deepest %.1f mm, landed %.1f mm from the reference)\n",
                  sim::to_string(in), h * 1e3, ok ? "correct" : "wrong", f.max_depth * 1e3,
                  f.finite ? (f.final_position - reference.final_position).norm() * 1e3 : -1.0);
      // the largest step of an unbroken run of correct ones from the smallest
      if (ok && (largest[static_cast<int>(in)] == 0 || largest[static_cast<int>(in)] * 2.5 >= h)) {
        largest[static_cast<int>(in)] = h;
      }
    }
  }
  std::printf(
      "largest correct step: implicit %.2f ms, semi-implicit %.2f ms, RK4 %.2f ms "
      "(implicit / semi-implicit %.0f×, implicit / RK4 %.0f×; the book: ≈16× and ≈4×)\n",
      largest[0] * 1e3, largest[1] * 1e3, largest[2] * 1e3, largest[0] / largest[1],
      largest[0] / largest[2]);
  EXPECT_TRUE(correct(drop_box(Integrator::kImplicit, 2e-3), reference));  // the book's 2 ms
  EXPECT_GE(largest[0], 16 * largest[1]);
  EXPECT_GE(largest[0], 4 * largest[2]);
}

TEST(Integrators, FreeFallFollowsHalfGTSquared) {
  for (const Integrator in : {Integrator::kImplicit, Integrator::kSemiImplicit, Integrator::kRk4}) {
    sim::WorldSettings s;
    s.integrator = in;
    sim::World w(s);
    sim::PropShape shape;
    auto m = sim::make_prop("ball", {core::Geometry::Shape::kSphere, {}, 0.1, 0}, 1.0);
    Eigen::VectorXd q = core::neutral_configuration(*m);
    q[1] = 10;
    w.add_body("ball", m, q);
    sim::Scene scene;
    scene.gravity = scene.ground_contact = true;
    w.set_scene(scene);
    w.advance(1.0);
    const double t = w.time();
    // semi-implicit Euler is exact up to one step's worth of drop: y error <= g h t
    const double tol = in == Integrator::kRk4 ? 1e-9 : 9.81 * s.step * t;
    EXPECT_NEAR(w.body(0).q[1], 10 - 0.5 * 9.81 * t * t, tol) << sim::to_string(in);
  }
}

TEST(Integrators, ADroppedBoxNeverGainsEnergy) {
  for (const Integrator in : {Integrator::kImplicit, Integrator::kRk4}) {
    const Fall f = drop_box(in, in == Integrator::kImplicit ? 1e-3 : 2.5e-4);
    EXPECT_TRUE(f.finite);
    EXPECT_LE(f.max_gain, 1e-6) << sim::to_string(in);
  }
}

// the weight a resting body puts on the ground: the pair's normal force, averaged over 1 s
double resting_load(const std::shared_ptr<const core::Model>& m,
                    double center_height,
                    const core::Quaternion& R,
                    int expected_points,
                    double& drift) {
  sim::World w;
  Eigen::VectorXd q = core::neutral_configuration(*m);
  q[1] = center_height;
  core::set_quaternion_at(q, 3, R);
  w.add_body("prop", m, q);
  sim::Scene scene;
  scene.gravity = scene.ground_contact = scene.friction = true;
  w.set_scene(scene);
  w.advance(1.0);  // settle
  EXPECT_EQ(static_cast<int>(w.contact_points().size()), expected_points);
  const Eigen::VectorXd q_settled = w.body(0).q;
  double load = 0;
  for (int k = 0; k < 1000; ++k) {
    w.step();
    for (const sim::ContactPair& p : w.contact_pairs()) load += p.wrench[4] / 1000;
  }
  w.advance(9.0);
  drift = (w.body(0).q.head<3>() - q_settled.head<3>()).norm();
  return load;
}

TEST(Integrators, RestingLoadIsTheWeightWhateverThePointCount) {
  const double mg = 2.0 * 9.81;
  const core::Quaternion lying = core::Quaternion::Identity();  // capsules run along z
  double drift = 0;
  sim::PropShape box;
  box.size = core::Vector3(0.3, 0.2, 0.1);
  const double on_corners =
      resting_load(sim::make_prop("box", box, 2.0), 0.1, core::Quaternion::Identity(), 4, drift);
  EXPECT_NEAR(on_corners, mg, 0.01 * mg);
  EXPECT_LT(drift, 1e-6);
  const double on_two =
      resting_load(sim::make_prop("capsule", {core::Geometry::Shape::kCapsule, {}, 0.05, 0.4}, 2.0),
                   0.05, lying, 2, drift);
  EXPECT_NEAR(on_two, mg, 0.01 * mg);
  EXPECT_LT(drift, 1e-6);
  const double on_one =
      resting_load(sim::make_prop("ball", {core::Geometry::Shape::kSphere, {}, 0.1, 0}, 2.0), 0.1,
                   core::Quaternion::Identity(), 1, drift);
  EXPECT_NEAR(on_one, mg, 0.01 * mg);
  EXPECT_LT(drift, 1e-6);
  std::printf("resting load of a 2 kg prop on 4 / 2 / 1 points: %.4f / %.4f / %.4f N (mg %.4f)\n",
              on_corners, on_two, on_one, mg);
}

}  // namespace
