#include "core/osim.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "core/crba.hpp"

namespace core {

void handle_jacobian(const Model& model,
                     const Data& data,
                     const std::vector<Handle>& handles,
                     Eigen::MatrixXd& J) {
  int m = 0;
  for (const Handle& h : handles) m += h.rows();
  if (J.rows() != m || J.cols() != model.nv) J.resize(m, model.nv);
  J.setZero();
  int row = 0;
  for (const Handle& h : handles) {
    // only the columns on the link's root path are nonzero: written straight into the rows
    write_point_jacobian_rows(model, data, h.link, data.X_W[h.link] * h.p_LinkPoint,
                              h.with_orientation ? row : -1, h.with_orientation ? row + 3 : row, J);
    row += h.rows();
  }
}

void inverse_operational_inertia(const Model& model,
                                 const Data& data,
                                 const std::vector<Handle>& handles,
                                 OsimWorkspace& ws,
                                 Eigen::MatrixXd& Phi) {
  handle_jacobian(model, data, handles, ws.J);
  const Eigen::Index m = ws.J.rows();
  if (ws.Y.rows() != model.nv || ws.Y.cols() != m) ws.Y.resize(model.nv, m);
  // Φ = J H⁻¹ Jᵀ = Yᵀ Y with Y = D^-1/2 L⁻ᵀ Jᵀ
  Eigen::VectorXd& scale = ws.inverse_sqrt_pivots;
  if (scale.size() != model.nv) scale.resize(model.nv);
  for (int k = 0; k < model.nv; ++k) scale[k] = 1.0 / std::sqrt(data.LTDL(k, k));
  ws.Y = ws.J.transpose();
  // a handle's columns of Jᵀ, and so of Y, are zero off its link's root path
  int r = 0;
  for (const Handle& h : handles) {
    solve_mass_matrix_lt_on_path(model, data, model.path_last_v(h.link),
                                 ws.Y.middleCols(r, h.rows()));
    r += h.rows();
  }
  for (Eigen::Index c = 0; c < m; ++c) ws.Y.col(c).array() *= scale.array();
  if (Phi.rows() != m || Phi.cols() != m) Phi.resize(m, m);
  // Φ is symmetric: the lower triangle's products only, then mirrored
  Phi.triangularView<Eigen::Lower>() = ws.Y.transpose() * ws.Y;
  Phi.triangularView<Eigen::StrictlyUpper>() = Phi.transpose();
}

int operational_inertia(const Eigen::MatrixXd& Phi, Eigen::MatrixXd& Lambda, double rel_tol) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Phi);
  const Eigen::VectorXd& ev = es.eigenvalues();
  const double cutoff = rel_tol * std::max(ev.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd inv = Eigen::VectorXd::Zero(ev.size());
  int rank = 0;
  for (Eigen::Index k = 0; k < ev.size(); ++k) {
    if (ev[k] > cutoff) {
      inv[k] = 1.0 / ev[k];
      ++rank;
    }
  }
  Lambda = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
  return rank;
}

void floating_base_split(const Model& model,
                         const Data& data,
                         const std::vector<Handle>& handles,
                         const Eigen::VectorXd& bias,
                         FloatingBaseSplit& out) {
  const int nv = model.nv;
  const int nq_joints = nv - 6;
  handle_jacobian(model, data, handles, out.J);  // resizes only on a new size
  const int m = static_cast<int>(out.J.rows());
  out.H_bb = data.M.topLeftCorner<6, 6>();
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> Hbb(out.H_bb);
  out.J_b = out.J.leftCols<6>();
  // X = J_b H_bb⁻¹ (m x 6), through Xᵀ = H_bb⁻¹ J_bᵀ
  out.X_t = out.J_b.transpose();
  Hbb.solveInPlace(out.X_t);
  out.X = out.X_t.transpose();
  // Γ = J_q − X H_bq and Φ^lock = X J_bᵀ, without Eigen's temporaries for the products
  out.Gamma = out.J.rightCols(nq_joints);
  out.Gamma.noalias() -= out.X * data.M.topRightCorner(6, nq_joints);
  out.Phi_lock.noalias() = out.X * out.J_b.transpose();
  // ψ = J̇v − J_b H_bb⁻¹ b_b
  if (out.psi.size() != m) out.psi.resize(m);
  int row = 0;
  for (const Handle& h : handles) {
    const PointMotion jdv = point_jdot_v(model, data, h.link, h.p_LinkPoint);
    if (h.with_orientation) {
      out.psi.segment<3>(row) = jdv.angular;
      row += 3;
    }
    out.psi.segment<3>(row) = jdv.linear;
    row += 3;
  }
  out.psi.noalias() -= out.X * bias.head<6>();
}

}  // namespace core
