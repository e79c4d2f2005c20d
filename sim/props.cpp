#include "sim/props.hpp"

#include <cmath>
#include <numbers>

#include "core/model_builder.hpp"

namespace sim {

namespace {

bool positive(double x) { return std::isfinite(x) && x > 0; }

// rotational inertia about the centre of mass, solid and uniform
core::Matrix3 box_inertia(double m, const core::Vector3& s) {
  const core::Vector3 s2 = s.cwiseProduct(s);
  return (m / 12.0) * core::Vector3(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
}

core::Matrix3 capsule_inertia(double m, double r, double l) {
  // a cylinder of height l and two hemispheres of radius r, mass split by volume
  const double pi = std::numbers::pi;
  const double v_cyl = pi * r * r * l;
  const double v_sph = 4.0 / 3.0 * pi * r * r * r;
  const double m_cyl = m * v_cyl / (v_cyl + v_sph);
  const double m_sph = m - m_cyl;
  const double axial = m_cyl * r * r / 2 + m_sph * 2 * r * r / 5;
  // each hemisphere about its own centre of mass (3r/8 from the flat face), then shifted
  const double d = l / 2 + 3 * r / 8;
  const double hemi = 83.0 / 320.0 * (m_sph / 2) * r * r + (m_sph / 2) * d * d;
  const double transverse = m_cyl * (r * r / 4 + l * l / 12) + 2 * hemi;
  return core::Vector3(transverse, transverse, axial).asDiagonal();
}

}  // namespace

std::shared_ptr<const core::Model> make_prop(const std::string& name,
                                             const PropShape& shape,
                                             double mass) {
  auto fail = [&](const std::string& rule) -> std::shared_ptr<const core::Model> {
    throw core::ModelError({"prop '" + name + "': " + rule});
  };
  if (!positive(mass)) return fail("mass must be a finite number > 0");
  core::Geometry g;
  g.shape = shape.shape;
  core::LinkSpec link;
  link.name = name.empty() ? "prop" : name;
  link.joint.type = core::JointType::kFree;
  link.mass = mass;
  switch (shape.shape) {
    case core::Geometry::Shape::kBox:
      if (!shape.size.allFinite() || (shape.size.array() <= 0).any()) {
        return fail("size must be three finite numbers > 0");
      }
      g.size = shape.size;
      link.I_com = box_inertia(mass, shape.size);
      break;
    case core::Geometry::Shape::kSphere:
      if (!positive(shape.radius)) return fail("radius must be a finite number > 0");
      g.radius = shape.radius;
      link.I_com = core::Matrix3::Identity() * (0.4 * mass * shape.radius * shape.radius);
      break;
    case core::Geometry::Shape::kCapsule:
      if (!positive(shape.radius)) return fail("radius must be a finite number > 0");
      if (!std::isfinite(shape.length) || shape.length < 0) {
        return fail("length must be a finite number >= 0");
      }
      g.radius = shape.radius;
      g.length = shape.length;
      link.I_com = capsule_inertia(mass, shape.radius, shape.length);
      break;
    default:
      return fail("shape must be a box, a sphere or a capsule");
  }
  link.collision.push_back(g);
  link.visual.push_back(g);
  core::ModelBuilder builder(link.name);
  builder.add_link(std::move(link));
  return builder.finalize();
}

}  // namespace sim
