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

void ltdl_factorize(const Model& model, Eigen::Ref<Eigen::MatrixXd> H) {
  const std::vector<int>& lambda = model.parent_v;
  // LTDL (RBDA Table 6.3): eliminate from the leaves up, touching only ancestor pairs. The
  // elimination runs on the transposed (upper) positions, H(j, i) standing for H(i, j) with j an
  // ancestor of i: walking the ancestors then reads down a column, which is contiguous wherever
  // coordinates are numbered consecutively (limbs, chains), instead of across a row (a cache miss
  // per entry once the matrix outgrows the cache: 2x on a 512-link chain). Same operations,
  // same results; L goes back to the lower triangle as documented.
  for (int k = 1; k < model.nv; ++k) {
    for (int i = lambda[k]; i >= 0; i = lambda[i]) H(i, k) = H(k, i);
  }
  for (int k = model.nv - 1; k >= 0; --k) {
    double* Hk = &H(0, k);  // Hk[j] = H(k, j) for the ancestors j of k
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      const double a = Hk[i] / Hk[k];
      double* Hi = &H(0, i);
      for (int j = i; j >= 0; j = lambda[j]) Hi[j] -= a * Hk[j];
      Hk[i] = a;
    }
    for (int i = lambda[k]; i >= 0; i = lambda[i]) H(k, i) = Hk[i];
  }
}

void ltdl_solve_lt(const Model& model,
                   const Eigen::Ref<const Eigen::MatrixXd>& L,
                   Eigen::Ref<Eigen::VectorXd> x) {
  for (int k = model.nv - 1; k >= 0; --k) {
    const double xk = x[k];
    if (xk == 0) continue;
    for (int i = model.parent_v[k]; i >= 0; i = model.parent_v[i]) x[i] -= L(k, i) * xk;
  }
}

void ltdl_solve_l(const Model& model,
                  const Eigen::Ref<const Eigen::MatrixXd>& L,
                  Eigen::Ref<Eigen::VectorXd> x) {
  for (int k = 0; k < model.nv; ++k) {
    for (int i = model.parent_v[k]; i >= 0; i = model.parent_v[i]) x[k] -= L(k, i) * x[i];
  }
}

void ltdl_solve(const Model& model,
                const Eigen::Ref<const Eigen::MatrixXd>& L,
                Eigen::Ref<Eigen::VectorXd> x) {
  // H⁻¹ = L⁻¹ D⁻¹ L⁻ᵀ
  ltdl_solve_lt(model, L, x);
  for (int k = 0; k < model.nv; ++k) x[k] /= L(k, k);
  ltdl_solve_l(model, L, x);
}

void factorize_mass_matrix(const Model& model, Data& data) {
  data.LTDL = data.M;
  ltdl_factorize(model, data.LTDL);
}

void solve_mass_matrix_lt(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> x) {
  ltdl_solve_lt(model, data.LTDL, x);
}

void solve_mass_matrix(const Model& model, const Data& data, Eigen::Ref<Eigen::VectorXd> b) {
  ltdl_solve(model, data.LTDL, b);
}

void solve_mass_matrix_columns(const Model& model,
                               const Data& data,
                               Eigen::Ref<Eigen::MatrixXd> B) {
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    Eigen::Ref<Eigen::VectorXd> col(B.col(c));
    solve_mass_matrix(model, data, col);
  }
}

}  // namespace core
