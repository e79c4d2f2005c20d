#include "core/bounds.hpp"

#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace core {

namespace {
void add_shape(const Transform& X_WS, const Geometry& g, Bounds& b) {
  const Vector3 z = X_WS.R.col(2);
  switch (g.shape) {
    case Geometry::Shape::kSphere:
      b.add(X_WS.p - Vector3::Constant(g.radius));
      b.add(X_WS.p + Vector3::Constant(g.radius));
      break;
    case Geometry::Shape::kCapsule:
      // the two end spheres bound the capsule
      for (double s : {-0.5, 0.5}) {
        b.add(X_WS.p + s * g.length * z - Vector3::Constant(g.radius));
        b.add(X_WS.p + s * g.length * z + Vector3::Constant(g.radius));
      }
      break;
    case Geometry::Shape::kCylinder:
    case Geometry::Shape::kBox: {
      const Vector3 half = g.shape == Geometry::Shape::kBox
                               ? Vector3(0.5 * g.size)
                               : Vector3(g.radius, g.radius, 0.5 * g.length);
      for (int corner = 0; corner < 8; ++corner) {
        const Vector3 c((corner & 1) ? half.x() : -half.x(), (corner & 2) ? half.y() : -half.y(),
                        (corner & 4) ? half.z() : -half.z());
        b.add(X_WS * c);
      }
      break;
    }
    case Geometry::Shape::kMesh:
      break;
  }
}
}  // namespace

Bounds world_bounds(const Model& model, const Data& data) {
  Bounds b;
  for (int i = 1; i < model.njoints; ++i) {
    b.add(data.X_W[i].p);
    for (const auto* shapes : {&model.collision[i], &model.visual[i]}) {
      for (const Geometry& g : *shapes) add_shape(data.X_W[i] * g.X_LinkShape, g, b);
    }
  }
  return b;
}

double neutral_height(const Model& model) {
  Data data(model);
  forward_kinematics(model, data, neutral_configuration(model));
  return world_bounds(model, data).size().y();
}

}  // namespace core
