#include "core/centroidal.hpp"

#include "core/com.hpp"

namespace core {

const Matrix6X& centroidal_momentum_matrix(const Model& model, Data& data) {
  center_of_mass(model, data);
  for (int i = 1; i < model.njoints; ++i) data.Ic_W[i] = model.inertia[i].transformed(data.X_W[i]);
  for (int i = model.njoints - 1; i > 1; --i) {
    if (model.parent[i] > 0) data.Ic_W[model.parent[i]] += data.Ic_W[i];
  }
  const Vector3& c = data.com_W;
  for (int k = 0; k < model.nv; ++k) {
    const Motion s = Motion::from_vector(data.J.col(k));
    const Force h_O = data.Ic_W[model.joint_of_v[k]] * s;  // about the world origin
    data.Ag.col(k).head<3>() = h_O.angular - c.cross(h_O.linear);
    data.Ag.col(k).tail<3>() = h_O.linear;
  }
  return data.Ag;
}

Force centroidal_momentum(const Model& model, Data& data) {
  center_of_mass(model, data);
  Force h_O;
  for (int i = 1; i < model.njoints; ++i) {
    h_O += data.X_W[i].act(model.inertia[i] * data.v[i]);
  }
  return {h_O.angular - data.com_W.cross(h_O.linear), h_O.linear};
}

double kinetic_energy(const Model& model, const Data& data) {
  double T = 0;
  for (int i = 1; i < model.njoints; ++i) T += 0.5 * (model.inertia[i] * data.v[i]).dot(data.v[i]);
  return T;
}

double potential_energy(const Model& model, const Data& data) {
  double V = 0;
  for (int i = 1; i < model.njoints; ++i) {
    const SpatialInertia& I = model.inertia[i];
    V -= I.mass * model.gravity.dot(data.X_W[i] * I.com());
  }
  return V;
}

}  // namespace core
