// Shared set-ups of the simulation tests: the book's box on a floor or a slope.
#pragma once

#include <cmath>
#include <memory>

#include "core/configuration.hpp"
#include "sim/props.hpp"
#include "sim/world.hpp"

namespace sim_fixtures {

/// A 1 kg, 0.2 m cube resting (at its equilibrium penetration) on a ground plane tilted by
/// `slope` radians about z (descending toward +x), sliding down the slope at `speed` m/s.
struct BoxOnGround {
  sim::World world;
  core::Vector3 down_slope;  // unit tangent pointing down the slope
  core::Vector3 normal;

  BoxOnGround(const sim::WorldSettings& settings,
              double speed,
              double slope = 0.0,
              double mass = 1.0)
      : world(settings, environment(slope)) {
    normal = world.environment().ground.normal;
    down_slope = core::Vector3(std::cos(slope), -std::sin(slope), 0);
    sim::PropShape shape;
    shape.size = core::Vector3(0.2, 0.2, 0.2);
    auto model = sim::make_prop("box", shape, mass);
    Eigen::VectorXd q = core::neutral_configuration(*model);
    const double sink = mass * 9.81 * std::cos(slope) / settings.contact.kp;
    q.head<3>() = normal * (0.1 - sink);
    const core::Quaternion R(Eigen::AngleAxisd(-slope, core::Vector3::UnitZ()));
    core::set_quaternion_at(q, 3, R);
    Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
    v.tail<3>() = R.conjugate() * (speed * down_slope);  // free-joint velocity: body axes
    world.add_body("box", model, q, v);
    sim::Scene scene;
    scene.gravity = scene.ground_contact = scene.friction = true;
    world.set_scene(scene);
  }

  static sim::Environment environment(double slope) {
    sim::Environment e;
    e.ground.normal = core::Vector3(std::sin(slope), std::cos(slope), 0);
    return e;
  }
  /// Position and velocity of the box's centre along the slope.
  double distance() const { return down_slope.dot(core::Vector3(world.body(0).q.head<3>())); }
  double speed() const {
    const Eigen::VectorXd& q = world.body(0).q;
    return down_slope.dot(core::quaternion_at(q, 3) * core::Vector3(world.body(0).v.tail<3>()));
  }
};

}  // namespace sim_fixtures
