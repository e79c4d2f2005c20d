#include "core/com.hpp"

namespace core {

const Vector3& center_of_mass(const Model& model, Data& data) {
  // subtree sums from the leaves up (parent[i] < i)
  for (int i = 0; i < model.njoints; ++i) {
    const SpatialInertia& I = model.inertia[i];
    data.subtree_mass[i] = I.mass;
    data.subtree_h_W[i] = i == 0 ? Vector3::Zero() : Vector3(I.mass * (data.X_W[i] * I.com()));
  }
  for (int i = model.njoints - 1; i > 0; --i) {
    data.subtree_mass[model.parent[i]] += data.subtree_mass[i];
    data.subtree_h_W[model.parent[i]] += data.subtree_h_W[i];
  }
  data.mass = data.subtree_mass[0];
  data.com_W = data.mass > 0 ? Vector3(data.subtree_h_W[0] / data.mass) : Vector3::Zero();
  return data.com_W;
}

const Matrix3X& com_jacobian(const Model& model, Data& data) {
  center_of_mass(model, data);
  data.J_com.setZero();
  if (data.mass <= 0) return data.J_com;
  const double inv_mass = 1.0 / data.mass;
  for (int c = 0; c < model.nv; ++c) {
    const int i = model.joint_of_v[c];
    const Vector3 w = data.J.col(c).head<3>();
    const Vector3 v = data.J.col(c).tail<3>();
    // Σ over moved links of m (v + ω × c) = M_sub v + ω × h_sub
    data.J_com.col(c) = inv_mass * (data.subtree_mass[i] * v + w.cross(data.subtree_h_W[i]));
  }
  return data.J_com;
}

}  // namespace core
