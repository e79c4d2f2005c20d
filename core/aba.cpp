#include "core/aba.hpp"

#include <Eigen/LU>

#include "core/kinematics.hpp"
#include "core/motion_subspace.hpp"

namespace core {

namespace {

// S_i as a fixed-size 6 x NV matrix
template <int NV>
Eigen::Matrix<double, 6, NV> subspace_matrix(const Model& model, int i) {
  Eigen::Matrix<double, 6, NV> S;
  for (int d = 0; d < NV; ++d) S.col(d) = subspace_column(model, i, d).vector();
  return S;
}

// pass 2 for one joint with NV coordinates: U = IA S, D⁻¹ = (Sᵀ U)⁻¹, u = τ − Sᵀ pA, then the
// articulated inertia and bias force the parent sees (RBDA Table 7.1)
template <int NV>
void articulate(const Model& model, Data& data, int i, const Eigen::VectorXd& tau, Matrix6& Ia,
                Vector6& pa) {
  const Eigen::Matrix<double, 6, NV> S = subspace_matrix<NV>(model, i);
  const Eigen::Matrix<double, 6, NV> U = data.IA[i] * S;
  const Eigen::Matrix<double, NV, NV> D = S.transpose() * U;
  const Eigen::Matrix<double, NV, NV> Dinv = D.inverse();  // D is SPD and at most 6 x 6
  const Eigen::Matrix<double, NV, 1> u = tau.segment<NV>(model.idx_v[i]) - S.transpose() * pa;
  data.U[i].leftCols<NV>() = U;
  data.Dinv[i].topLeftCorner<NV, NV>() = Dinv;
  data.u[i].head<NV>() = u;
  Ia.noalias() -= U * Dinv * U.transpose();
  pa += Ia * data.c[i].vector() + U * (Dinv * u);
}

// pass 3 for one joint: q̈ = D⁻¹ (u − Uᵀ a'), a = a' + S q̈
template <int NV>
void accelerate(const Model& model, Data& data, int i, Motion& a) {
  const Eigen::Matrix<double, NV, 1> qdd =
      data.Dinv[i].topLeftCorner<NV, NV>() *
      (data.u[i].head<NV>() - data.U[i].leftCols<NV>().transpose() * a.vector());
  data.ddq.segment<NV>(model.idx_v[i]) = qdd;
  a = Motion::from_vector(a.vector() + subspace_matrix<NV>(model, i) * qdd);
}

const Eigen::VectorXd& aba_impl(const Model& model, Data& data, const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v, const Eigen::VectorXd& tau,
                                const std::vector<Force>* f_ext) {
  // pass 1, root to leaves: velocities, velocity-product terms, body inertias and bias forces
  data.v[0] = Motion::Zero();
  for (int i = 1; i < model.njoints; ++i) {
    data.X_P[i] = joint_transform(model, i, q);
    const Motion vJ = joint_motion(model, i, v);
    data.v[i] = data.X_P[i].act_inverse(data.v[model.parent[i]]) + vJ;
    data.c[i] = data.v[i].cross(vJ);
    const SpatialInertia& I = model.inertia[i];
    data.IA[i] = I.matrix();
    data.pA[i] = cross(data.v[i], I * data.v[i]);
    if (f_ext) data.pA[i] -= (*f_ext)[i];
  }
  // pass 2, leaves to root: articulated inertias and bias forces
  for (int i = model.njoints - 1; i > 0; --i) {
    Matrix6 Ia = data.IA[i];
    Vector6 pa = data.pA[i].vector();
    switch (joint_nv(model.joint_type[i])) {
      case 0: pa += Ia * data.c[i].vector(); break;
      case 1: articulate<1>(model, data, i, tau, Ia, pa); break;
      case 3: articulate<3>(model, data, i, tau, Ia, pa); break;
      case 6: articulate<6>(model, data, i, tau, Ia, pa); break;
    }
    const int p = model.parent[i];
    if (p > 0) {
      // IA_p += X⁻ᵀ Ia X⁻¹ with X the motion transform child → parent
      const Matrix6 Y = data.X_P[i].inverse().motion_matrix();
      data.IA[p].noalias() += Y.transpose() * Ia * Y;
      data.pA[p] += data.X_P[i].act(Force::from_vector(pa));
    }
  }
  // pass 3, root to leaves: accelerations (gravity as an upward acceleration of the world)
  data.a[0] = {Vector3::Zero(), -model.gravity};
  for (int i = 1; i < model.njoints; ++i) {
    Motion a = data.X_P[i].act_inverse(data.a[model.parent[i]]) + data.c[i];
    switch (joint_nv(model.joint_type[i])) {
      case 1: accelerate<1>(model, data, i, a); break;
      case 3: accelerate<3>(model, data, i, a); break;
      case 6: accelerate<6>(model, data, i, a); break;
      default: break;
    }
    data.a[i] = a;
  }
  return data.ddq;
}

}  // namespace

const Eigen::VectorXd& aba(const Model& model, Data& data, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v, const Eigen::VectorXd& tau) {
  return aba_impl(model, data, q, v, tau, nullptr);
}

const Eigen::VectorXd& aba(const Model& model, Data& data, const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v, const Eigen::VectorXd& tau,
                           const std::vector<Force>& f_ext) {
  return aba_impl(model, data, q, v, tau, &f_ext);
}

}  // namespace core
