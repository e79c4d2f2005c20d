// Axis-aligned bounds of a posed figure: link origins and the extent of its primitive shapes.
#pragma once

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

struct Bounds {
  Vector3 min = Vector3::Constant(kInfinity);
  Vector3 max = Vector3::Constant(-kInfinity);
  bool empty() const { return (min.array() > max.array()).any(); }
  void add(const Vector3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  Vector3 size() const { return empty() ? Vector3::Zero() : Vector3(max - min); }
};

/// World bounds of every link origin and every primitive collision and visual shape (capsules,
/// spheres, boxes, cylinders; meshes contribute their link origin only).
/// Requires: forward_kinematics(model, data, q).
Bounds world_bounds(const Model& model, const Data& data);

/// Height of the figure at the neutral configuration: the vertical (Y) extent of world_bounds.
double neutral_height(const Model& model);

}  // namespace core
