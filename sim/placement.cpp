#include "sim/placement.hpp"

#include <cmath>
#include <limits>

#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "sim/shapes.hpp"

namespace sim {

double lowest_point_height(const core::Model& model,
                           const Eigen::VectorXd& q,
                           const GroundPlane& ground) {
  core::Data data(model);
  core::forward_kinematics(model, data, q);
  const BodyShapes shapes = build_body_shapes(model, q);
  double lowest = std::numeric_limits<double>::infinity();
  const core::Vector3& n = ground.normal;
  for (int i = 1; i < model.njoints; ++i) {
    for (const LinkShape& s : shapes.shapes[i]) {
      const core::Transform X_WS = data.X_W[i] * s.X_LinkShape;
      double h = n.dot(X_WS.p - ground.point);
      switch (s.kind) {
        case LinkShape::Kind::kSphere:
          h -= s.radius;
          break;
        case LinkShape::Kind::kCapsule:
          h -= s.radius + s.half_length * std::abs(n.dot(X_WS.R.col(2)));
          break;
        case LinkShape::Kind::kBox:
          // the support of a box along −n: Σ h_k |n · axis_k|
          for (int k = 0; k < 3; ++k) h -= s.half_extents[k] * std::abs(n.dot(X_WS.R.col(k)));
          break;
      }
      lowest = std::min(lowest, h);
    }
  }
  return lowest;
}

Eigen::VectorXd place_on_ground(const core::Model& model,
                                const Eigen::VectorXd& q,
                                const GroundPlane& ground,
                                double depth) {
  if (model.njoints < 2 || model.joint_type[1] != core::JointType::kFree) return q;
  const double h = lowest_point_height(model, q, ground);
  if (!std::isfinite(h)) return q;
  Eigen::VectorXd out = q;
  // the free root's position is in its joint placement's frame: X_WRoot = X_PJ X_J(q)
  out.head<3>() -= (h + depth) * (model.X_PJ[1].R.transpose() * ground.normal);
  return out;
}

}  // namespace sim
