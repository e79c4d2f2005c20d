#include "sim/placement.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "sim/shapes.hpp"

namespace sim {

namespace {

// Height above the plane of the lowest point of one shape placed at X_WS (the support along −n).
double shape_height(const LinkShape& s, const core::Transform& X_WS, const GroundPlane& ground) {
  const core::Vector3& n = ground.normal;
  double h = n.dot(X_WS.p - ground.point);
  switch (s.kind) {
    case LinkShape::Kind::kSphere:
      return h - s.radius;
    case LinkShape::Kind::kCapsule:
      return h - s.radius - s.half_length * std::abs(n.dot(X_WS.R.col(2)));
    case LinkShape::Kind::kBox:
      // the support of a box along −n: Σ h_k |n · axis_k|
      for (int k = 0; k < 3; ++k) h -= s.half_extents[k] * std::abs(n.dot(X_WS.R.col(k)));
      return h;
  }
  return h;
}

}  // namespace

double lowest_point_height(const core::Model& model,
                           const Eigen::VectorXd& q,
                           const GroundPlane& ground) {
  core::Data data(model);
  core::forward_kinematics(model, data, q);
  const BodyShapes shapes = build_body_shapes(model, q);
  double lowest = std::numeric_limits<double>::infinity();
  for (int i = 1; i < model.njoints; ++i) {
    for (const LinkShape& s : shapes.shapes[i]) {
      lowest = std::min(lowest, shape_height(s, data.X_W[i] * s.X_LinkShape, ground));
    }
  }
  return lowest;
}

namespace {

// the lowest point of a link's shapes above the plane (+inf without shapes), and the box among
// them whose face is nearest the ground
double link_height(const std::vector<LinkShape>& shapes,
                   const core::Transform& X_WL,
                   const GroundPlane& ground,
                   const LinkShape** box) {
  double lowest = std::numeric_limits<double>::infinity();
  *box = nullptr;
  for (const LinkShape& s : shapes) {
    const double h = shape_height(s, X_WL * s.X_LinkShape, ground);
    if (s.kind == LinkShape::Kind::kBox && (h < lowest || !*box)) *box = &s;
    lowest = std::min(lowest, h);
  }
  return lowest;
}

// the world rotation that lays the box's face nearest the ground flat on it
core::Matrix3 levelling_turn(const LinkShape& box,
                             const core::Transform& X_WL,
                             const core::Vector3& n) {
  const core::Matrix3 R = X_WL.R * box.X_LinkShape.R;
  int k = 0;
  const Eigen::Vector3d dots = (R.transpose() * n).cwiseAbs();
  dots.maxCoeff(&k);
  const core::Vector3 axis = R.col(k) * (R.col(k).dot(n) > 0 ? -1.0 : 1.0);  // points down
  return core::Quaternion::FromTwoVectors(axis, -n).toRotationMatrix();
}

}  // namespace

Eigen::VectorXd standing_configuration(const core::Model& model,
                                       const Eigen::VectorXd& q,
                                       const GroundPlane& ground,
                                       double reach) {
  Eigen::VectorXd out = q;
  const BodyShapes shapes = build_body_shapes(model, q);
  core::Data data(model);
  core::forward_kinematics(model, data, out);
  const double lowest = lowest_point_height(model, out, ground);
  if (!std::isfinite(lowest)) return place_on_ground(model, out, ground);
  for (int i = 1; i < model.njoints; ++i) {
    const LinkShape* box = nullptr;
    if (link_height(shapes.shapes[i], data.X_W[i], ground, &box) > lowest + reach || !box) continue;
    const core::Matrix3 turn = levelling_turn(*box, data.X_W[i], ground.normal);
    // the joint frame in the world: X_W[parent] X_PJ
    const core::Matrix3 R_WJ = data.X_W[model.parent[i]].R * model.X_PJ[i].R;
    const int iq = model.idx_q[i];
    if (model.joint_type[i] == core::JointType::kSpherical) {
      const core::Matrix3 R_J = R_WJ.transpose() * turn * R_WJ;
      core::set_quaternion_at(out, iq,
                              (core::Quaternion(R_J) * core::quaternion_at(out, iq)).normalized());
    } else if (model.joint_type[i] == core::JointType::kRevolute) {
      // the part of the turn about the joint's axis
      const core::Vector3 a_W = (R_WJ * model.axis[i]).normalized();
      const core::Vector3 w = core::log3(turn);
      const double angle = w.dot(a_W);
      out[iq] = std::clamp(out[iq] + angle, model.limits[i].lower, model.limits[i].upper);
    } else {
      continue;
    }
    core::forward_kinematics(model, data, out);
  }
  return place_on_ground(model, out, ground);
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

std::vector<int> supporting_links(const core::Model& model,
                                  const Eigen::VectorXd& q,
                                  const GroundPlane& ground,
                                  double reach) {
  const BodyShapes shapes = build_body_shapes(model, q);
  core::Data data(model);
  core::forward_kinematics(model, data, q);
  std::vector<char> supporting(model.njoints, 0);
  std::vector<int> out;
  for (int i = 1; i < model.njoints; ++i) {
    const LinkShape* box = nullptr;
    supporting[i] = link_height(shapes.shapes[i], data.X_W[i], ground, &box) <= reach;
    if (supporting[i] && !supporting[model.parent[i]]) out.push_back(i);
  }
  return out;
}

}  // namespace sim
