#include "core/crba.hpp"

#include "core/kinematics.hpp"
#include "core/motion_subspace.hpp"

namespace core {

const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q) {
  // composite inertias start as body inertias
  for (int i = 1; i < model.njoints; ++i) {
    data.X_P[i] = joint_transform(model, i, q);
    data.Ic[i] = model.inertia[i];
  }
  // backward pass: fill the rows and columns of each joint, then pass the composite up
  for (int i = model.njoints - 1; i > 0; --i) {
    const int nvi = joint_nv(model.joint_type[i]);
    const int ci = model.idx_v[i];
    for (int d = 0; d < nvi; ++d) {
      // F = Ic_i S_i,d is the force that accelerates the subtree along this coordinate
      Force F = data.Ic[i] * subspace_column(model, i, d);
      subspace_transpose(model, i, F, data.M.col(ci + d).segment(ci, nvi));
      for (int j = i; model.parent[j] > 0;) {
        F = data.X_P[j].act(F);
        j = model.parent[j];
        const int nvj = joint_nv(model.joint_type[j]);
        subspace_transpose(model, j, F, data.M.col(ci + d).segment(model.idx_v[j], nvj));
        data.M.row(ci + d).segment(model.idx_v[j], nvj) =
            data.M.col(ci + d).segment(model.idx_v[j], nvj).transpose();
      }
    }
    // the diagonal block is symmetric: mirror it so M is symmetric to the last bit
    auto block = data.M.block(ci, ci, nvi, nvi);
    block.triangularView<Eigen::StrictlyUpper>() = block.transpose();
    const int p = model.parent[i];
    if (p > 0) data.Ic[p] += data.Ic[i].transformed(data.X_P[i]);
  }
  return data.M;
}

void factorize_mass_matrix(const Model& model, Data& data) {
  Eigen::MatrixXd& H = data.LTDL;
  H = data.M;
  const std::vector<int>& lambda = model.parent_v;
  // LTDL (RBDA Table 6.3): eliminate from the leaves up, touching only ancestor pairs
  for (int k = model.nv - 1; k >= 0; --k) {
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      const double a = H(k, i) / H(k, k);
      for (int j = i; j >= 0; j = lambda[j]) H(i, j) -= a * H(k, j);
      H(k, i) = a;
    }
  }
}

void solve_mass_matrix_lt(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  const Eigen::MatrixXd& L = data.LTDL;
  for (int k = model.nv - 1; k >= 0; --k) {
    for (int i = model.parent_v[k]; i >= 0; i = model.parent_v[i]) x[i] -= L(k, i) * x[k];
  }
}

void solve_mass_matrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> b) {
  const Eigen::MatrixXd& L = data.LTDL;
  // H⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ
  solve_mass_matrix_lt(model, data, b);
  for (int k = 0; k < model.nv; ++k) b[k] /= L(k, k);
  for (int k = 0; k < model.nv; ++k) {
    for (int i = model.parent_v[k]; i >= 0; i = model.parent_v[i]) b[k] -= L(k, i) * b[i];
  }
}

void solve_mass_matrix_columns(const Model& model, const Data& data,
                               Eigen::Ref<Eigen::MatrixXd> B) {
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    Eigen::Ref<Eigen::VectorXd> col(B.col(c));
    solve_mass_matrix(model, data, col);
  }
}

}  // namespace core
