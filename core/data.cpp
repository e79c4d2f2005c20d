#include "core/data.hpp"

namespace core {

Data::Data(const Model& model)
    : X_P(model.njoints),
      X_W(model.njoints),
      v(model.njoints),
      a_bias(model.njoints),
      a(model.njoints),
      f(model.njoints),
      tau(Eigen::VectorXd::Zero(model.nv)),
      Ic(model.njoints),
      crba_X_W(model.njoints),
      crba_S(Matrix6X::Zero(6, model.nv)),
      crba_F(Eigen::MatrixXd::Zero(model.nv, 6)),
      M(Eigen::MatrixXd::Zero(model.nv, model.nv)),
      LTDL(Eigen::MatrixXd::Zero(model.nv, model.nv)),
      IA(model.njoints, Matrix6::Zero()),
      pA(model.njoints),
      c(model.njoints),
      U(model.njoints, Matrix6::Zero()),
      Dinv(model.njoints, Matrix6::Zero()),
      u(model.njoints, Vector6::Zero()),
      ddq(Eigen::VectorXd::Zero(model.nv)),
      J(Matrix6X::Zero(6, model.nv)),
      subtree_mass(model.njoints, 0.0),
      subtree_h_W(model.njoints, Vector3::Zero()),
      Ic_W(model.njoints),
      Ag(Matrix6X::Zero(6, model.nv)),
      J_com(Matrix3X::Zero(3, model.nv)) {}

}  // namespace core
