#include "sim/shapes.hpp"

#include <algorithm>

#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "sim/geometry.hpp"

namespace sim {

namespace {

using core::Geometry;
using core::Vector3;

bool to_link_shape(const Geometry& g, int index, LinkShape& out) {
  out.index = index;
  out.X_LinkShape = g.X_LinkShape;
  switch (g.shape) {
    case Geometry::Shape::kSphere:
      out.kind = LinkShape::Kind::kSphere;
      out.radius = g.radius;
      return g.radius > 0;
    case Geometry::Shape::kCapsule:
      out.kind = LinkShape::Kind::kCapsule;
      out.radius = g.radius;
      out.half_length = 0.5 * g.length;
      return g.radius > 0;
    case Geometry::Shape::kCylinder:
      out.kind = LinkShape::Kind::kCapsule;
      out.radius = g.radius;
      out.half_length = std::max(0.0, 0.5 * g.length - g.radius);
      return g.radius > 0;
    case Geometry::Shape::kBox:
      out.kind = LinkShape::Kind::kBox;
      out.half_extents = 0.5 * g.size;
      return (g.size.array() > 0).all();
    case Geometry::Shape::kMesh:
      return false;
  }
  return false;
}

// bounding sphere of one shape, link frame
std::pair<Vector3, double> shape_sphere(const LinkShape& s) {
  const Vector3 c = s.X_LinkShape.p;
  switch (s.kind) {
    case LinkShape::Kind::kSphere:
      return {c, s.radius};
    case LinkShape::Kind::kCapsule:
      return {c, s.radius + s.half_length};
    case LinkShape::Kind::kBox:
      return {c, s.half_extents.norm()};
  }
  return {c, 0};
}

bool proxies_touch(const CapsuleProxy& a, const CapsuleProxy& b) {
  Vector3 ca, cb;
  const double d2 = segment_closest_points(a.a_W, a.b_W, b.a_W, b.b_W, ca, cb);
  const double r = a.radius + b.radius;
  return d2 < r * r;
}

}  // namespace

CapsuleProxy capsule_proxy(const LinkShape& s, const core::Transform& X_WLink) {
  const core::Transform X_WS = X_WLink * s.X_LinkShape;
  CapsuleProxy p;
  Vector3 axis = Vector3::UnitZ();
  double half = 0;
  switch (s.kind) {
    case LinkShape::Kind::kSphere:
      p.radius = s.radius;
      break;
    case LinkShape::Kind::kCapsule:
      p.radius = s.radius;
      half = s.half_length;
      break;
    case LinkShape::Kind::kBox: {
      int k = 0;
      s.half_extents.maxCoeff(&k);
      axis = Vector3::Unit(k);
      Vector3 others = s.half_extents;
      others[k] = std::numeric_limits<double>::infinity();
      p.radius = others.minCoeff();
      half = std::max(0.0, s.half_extents[k] - p.radius);
      break;
    }
  }
  const Vector3 d = X_WS.R * (half * axis);
  p.a_W = X_WS.p - d;
  p.b_W = X_WS.p + d;
  return p;
}

BodyShapes build_body_shapes(const core::Model& model, const Eigen::VectorXd& q_rest) {
  BodyShapes out;
  out.shapes.resize(model.njoints);
  out.bounds.resize(model.njoints);
  for (int i = 1; i < model.njoints; ++i) {
    const auto& geoms = model.collision[i];
    for (int k = 0; k < static_cast<int>(geoms.size()); ++k) {
      LinkShape s;
      if (to_link_shape(geoms[k], k, s)) out.shapes[i].push_back(s);
    }
    if (out.shapes[i].empty()) continue;
    // a sphere around the shape spheres: centred on their mean, reaching the farthest one
    Vector3 c = Vector3::Zero();
    for (const LinkShape& s : out.shapes[i]) c += shape_sphere(s).first;
    c /= static_cast<double>(out.shapes[i].size());
    double r = 0;
    for (const LinkShape& s : out.shapes[i]) {
      const auto [sc, sr] = shape_sphere(s);
      r = std::max(r, (sc - c).norm() + sr);
    }
    out.bounds[i] = {c, r};
  }
  // self pairs: every pair of links with shapes, minus parents and children and pairs whose
  // shapes already touch at rest
  core::Data data(model);
  core::forward_kinematics(model, data, q_rest);
  for (int i = 1; i < model.njoints; ++i) {
    if (out.shapes[i].empty()) continue;
    for (int j = i + 1; j < model.njoints; ++j) {
      if (out.shapes[j].empty() || model.parent[j] == i || model.parent[i] == j) continue;
      bool touching = false;
      for (const LinkShape& a : out.shapes[i]) {
        for (const LinkShape& b : out.shapes[j]) {
          touching = touching ||
                     proxies_touch(capsule_proxy(a, data.X_W[i]), capsule_proxy(b, data.X_W[j]));
        }
      }
      if (!touching) out.self_pairs.emplace_back(i, j);
    }
  }
  return out;
}

}  // namespace sim
