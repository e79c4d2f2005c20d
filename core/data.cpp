#include "core/data.hpp"

namespace core {

Data::Data(const Model& model)
    : X_P(model.njoints),
      X_W(model.njoints),
      v(model.njoints),
      a_bias(model.njoints),
      a(model.njoints),
      J(Matrix6X::Zero(6, model.nv)),
      subtree_mass(model.njoints, 0.0),
      subtree_h_W(model.njoints, Vector3::Zero()),
      J_com(Matrix3X::Zero(3, model.nv)) {}

}  // namespace core
