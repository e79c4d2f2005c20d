#include "core/aba.hpp"

#include <cmath>

#include "core/hinge.hpp"
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

// Ia_parent += [A B; Bᵀ D], entry by entry: Eigen's strided block += on a 6 x 6 was an
// out-of-line loop and a visible share of the profile
void add_blocks(const Matrix3& A, const Matrix3& B, const Matrix3& D, Matrix6& Ia_parent) {
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      Ia_parent(r, c) += A(r, c);
      Ia_parent(r, c + 3) += B(r, c);
      Ia_parent(r + 3, c) += B(c, r);
      Ia_parent(r + 3, c + 3) += D(r, c);
    }
  }
}

// The articulated inertia of a child, given in the child frame C, as seen in its parent P:
// Ia_P = X_CPᵀ Ia_C X_CP with X_CP the motion transform P → C (RBDA eq. 2.66, Table 7.1 line
// "IA_λ += ..."). In 3 x 3 blocks Ia = [A B; Bᵀ D] and with X_PC = (R, p), P = [p×], the rotated
// blocks A' = R A Rᵀ, B' = R B Rᵀ, D' = R D Rᵀ give
//   Ia_P = [A' − (B'P + (B'P)ᵀ) − P D' P,  B' + P D';  (B' + P D')ᵀ,  D']
// which costs about a third of the two dense 6 x 6 products.
//
// add_shifted does the second step from the rotated blocks; a zero p (the coincident axes of a
// multi-axis joint) leaves them as they are.
void add_shifted(
    const Vector3& p, const Matrix3& A, const Matrix3& B, const Matrix3& D, Matrix6& Ia_parent) {
  if (p.x() == 0 && p.y() == 0 && p.z() == 0) {
    add_blocks(A, B, D, Ia_parent);
    return;
  }
  // products with P = [p×] as cross products: (P X).col(j) = p × X.col(j) and, as Pᵀ = −P,
  // (X P).row(j) = −(p × X.row(j)ᵀ)ᵀ
  Matrix3 PD, BP;
  for (int j = 0; j < 3; ++j) {
    PD.col(j) = p.cross(D.col(j));
    BP.row(j) = -p.cross(B.row(j).transpose()).transpose();
  }
  Matrix3 PDP;
  for (int j = 0; j < 3; ++j) PDP.row(j) = -p.cross(PD.row(j).transpose()).transpose();
  add_blocks(A - BP - BP.transpose() - PDP, B + PD, D, Ia_parent);
}

// the whole transform for any joint: rotate the blocks with the full R, then shift
void add_to_parent(const Transform& X_PC, const Matrix6& Ia, Matrix6& Ia_parent) {
  const Matrix3& R = X_PC.R;
  const Matrix3 A = R * Ia.topLeftCorner<3, 3>() * R.transpose();
  const Matrix3 B = R * Ia.topRightCorner<3, 3>() * R.transpose();
  const Matrix3 D = R * Ia.bottomRightCorner<3, 3>() * R.transpose();
  add_shifted(X_PC.p, A, B, D, Ia_parent);
}

// R M Rᵀ for R a rotation about principal axis K: rotate the columns, then the rows
template <int K>
Matrix3 congruence(const AxisRotation<K>& r, const Matrix3& M) {
  Matrix3 RM;
  for (int j = 0; j < 3; ++j) RM.col(j) = r.apply(M.col(j));
  Matrix3 out;
  for (int j = 0; j < 3; ++j) out.row(j) = r.apply(RM.row(j).transpose()).transpose();
  return out;
}

// R M Rᵀ for a symmetric M: only the entries that mix, in the plane of axes k1, k2
template <int K>
Matrix3 congruence_symmetric(const AxisRotation<K>& r, const Matrix3& M) {
  constexpr int k1 = AxisRotation<K>::k1, k2 = AxisRotation<K>::k2;
  const double c = r.c, s = r.s;
  const double a = M(k1, k1), b = M(k1, k2), d = M(k2, k2);
  const double cc = c * c, ss = s * s, cs = c * s;
  Matrix3 out;
  out(K, K) = M(K, K);
  out(K, k1) = out(k1, K) = c * M(K, k1) - s * M(K, k2);
  out(K, k2) = out(k2, K) = s * M(K, k1) + c * M(K, k2);
  out(k1, k1) = cc * a - 2 * cs * b + ss * d;
  out(k2, k2) = ss * a + 2 * cs * b + cc * d;
  out(k1, k2) = out(k2, k1) = cs * (a - d) + (cc - ss) * b;
  return out;
}

// pass 2 for a hinge (S = [e_K; 0]): U = IA S is column K of IA, D its entry K, u = τ − pA_K;
// then Ia = IA − U Uᵀ / D and pa = pA + Ia c + U u / D go to the parent through the hinge
// transform, whose rotation is applied to the 3 x 3 blocks directly (RBDA Table 7.1). Ia is
// symmetric, so only its three distinct blocks [A B; Bᵀ D] are formed (27 entries, not 36).
template <int K>
void articulate_hinge(Data& data, int i, int parent, double tau_i) {
  const Matrix6& IA = data.IA[i];
  const Vector6 U = IA.col(K);
  const double Dinv = 1.0 / U[K];
  const double u = tau_i - data.pA[i].angular[K];
  data.U[i].col(0) = U;
  data.Dinv[i](0, 0) = Dinv;
  data.u[i][0] = u;
  if (parent == 0) return;  // nothing above the root needs Ia or pa
  const Vector6 w = Dinv * U;
  Matrix3 A, B, D;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      A(r, c) = IA(r, c) - U[r] * w[c];
      B(r, c) = IA(r, c + 3) - U[r] * w[c + 3];
      D(r, c) = IA(r + 3, c + 3) - U[r + 3] * w[c + 3];
    }
  }
  // pa = pA + U u / D + Ia c with Ia c = [A c_ω + B c_v; Bᵀ c_ω + D c_v]
  const Motion& cm = data.c[i];
  const double g = Dinv * u;
  Vector3 pa_angular = data.pA[i].angular + U.head<3>() * g;
  Vector3 pa_linear = data.pA[i].linear + U.tail<3>() * g;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      pa_angular[r] += A(r, c) * cm.angular[c] + B(r, c) * cm.linear[c];
      pa_linear[r] += B(c, r) * cm.angular[c] + D(r, c) * cm.linear[c];
    }
  }
  const HingeTransform<K> X = HingeTransform<K>::of(data.X_P[i]);
  add_shifted(X.p, congruence_symmetric(X.r, A), congruence(X.r, B), congruence_symmetric(X.r, D),
              data.IA[parent]);
  data.pA[parent] += X.act(Force{pa_angular, pa_linear});
}

// The inverse of a symmetric positive-definite N x N matrix (N = 3 or 6: a joint's D = Sᵀ IA S)
// through its Cholesky factor D = L Lᵀ, unrolled at compile time: D⁻¹ = L⁻ᵀ L⁻¹. Eigen's general
// LU inverse of the 6 x 6 of a free root was a visible share of the profile.
template <int N>
Eigen::Matrix<double, N, N> spd_inverse(const Eigen::Matrix<double, N, N>& D) {
  double L[N][N] = {};
  double inv_diag[N];
  for (int j = 0; j < N; ++j) {
    double d = D(j, j);
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    L[j][j] = std::sqrt(d);
    inv_diag[j] = 1.0 / L[j][j];
    for (int i = j + 1; i < N; ++i) {
      double s = D(i, j);
      for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
      L[i][j] = s * inv_diag[j];
    }
  }
  // M = L⁻¹, lower triangular, column by column by forward substitution
  double M[N][N] = {};
  for (int j = 0; j < N; ++j) {
    M[j][j] = inv_diag[j];
    for (int i = j + 1; i < N; ++i) {
      double s = 0.0;
      for (int k = j; k < i; ++k) s += L[i][k] * M[k][j];
      M[i][j] = -s * inv_diag[i];
    }
  }
  // D⁻¹ = Mᵀ M: entry (r, c) sums over the rows k ≥ max(r, c) where both columns are nonzero
  Eigen::Matrix<double, N, N> out;
  for (int c = 0; c < N; ++c) {
    for (int r = c; r < N; ++r) {
      double s = 0.0;
      for (int k = r; k < N; ++k) s += M[k][r] * M[k][c];
      out(r, c) = out(c, r) = s;
    }
  }
  return out;
}

// pass 2 for one joint with NV coordinates: U = IA S, D⁻¹ = (Sᵀ U)⁻¹, u = τ − Sᵀ pA, then the
// articulated inertia and bias force the parent sees (RBDA Table 7.1)
template <int NV>
void articulate(
    const Model& model, Data& data, int i, const Eigen::VectorXd& tau, Matrix6& Ia, Vector6& pa) {
  const Eigen::Matrix<double, 6, NV> S = subspace_matrix<NV>(model, i);
  const Eigen::Matrix<double, 6, NV> U = data.IA[i] * S;
  const Eigen::Matrix<double, NV, NV> D = S.transpose() * U;
  const Eigen::Matrix<double, NV, NV> Dinv = spd_inverse<NV>(D);  // D is SPD (IA is)
  const Eigen::Matrix<double, NV, 1> u = tau.segment<NV>(model.idx_v[i]) - S.transpose() * pa;
  data.U[i].leftCols<NV>() = U;
  data.Dinv[i].topLeftCorner<NV, NV>() = Dinv;
  data.u[i].head<NV>() = u;
  if (model.parent[i] == 0) return;  // nothing above the root needs Ia or pa
  Ia = data.IA[i];
  Ia.noalias() -= U * Dinv * U.transpose();
  pa += Ia * data.c[i].vector() + U * (Dinv * u);
}

// pass 2 for a revolute or prismatic joint, the common case: S is one column [a; 0] or [0; a], so
// U = IA S is a 6 x 3 block times the axis (a column of IA for a frame axis), D is a scalar and
// the update of Ia is a symmetric rank-one product (same formulas as articulate<1>)
void articulate_1dof(
    const Model& model, Data& data, int i, const Eigen::VectorXd& tau, Matrix6& Ia, Vector6& pa) {
  // Ia is written here (not copied from IA first); pa holds pA_i on entry
  const bool revolute = model.joint_type[i] == JointType::kRevolute;
  const int k = model.axis_index[i];
  const int off = revolute ? 0 : 3;
  Vector6 U;
  if (k >= 0) {
    U = data.IA[i].col(off + k);
  } else {
    U.noalias() = data.IA[i].middleCols<3>(off) * model.axis[i];
  }
  const double D = k >= 0 ? U[off + k] : model.axis[i].dot(U.segment<3>(off));
  const double Dinv = 1.0 / D;
  const double u =
      tau[model.idx_v[i]] - (k >= 0 ? pa[off + k] : model.axis[i].dot(pa.segment<3>(off)));
  data.U[i].col(0) = U;
  data.Dinv[i](0, 0) = Dinv;
  data.u[i][0] = u;
  if (model.parent[i] == 0) return;  // nothing above the root needs Ia or pa
  Ia = data.IA[i] - (Dinv * U).lazyProduct(U.transpose());
  pa.noalias() += Ia * data.c[i].vector();
  pa += (Dinv * u) * U;
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

const Eigen::VectorXd& aba_impl(const Model& model,
                                Data& data,
                                const Eigen::VectorXd& q,
                                const Eigen::VectorXd& v,
                                const Eigen::VectorXd& tau,
                                const std::vector<Force>* f_ext) {
  // pass 1, root to leaves: velocities, velocity-product terms, body inertias and bias forces
  data.v[0] = Motion::Zero();
  for (int i = 1; i < model.njoints; ++i) {
    const Motion& v_parent = data.v[model.parent[i]];
    if (is_hinge(model, i)) {
      with_axis(model.axis_index[i], [&](auto axis) {
        constexpr int k = axis();
        const HingeTransform<k> X{hinge_rotation<k>(model, i, q), model.X_PJ[i].p};
        const double qd = v[model.idx_v[i]];
        data.X_P[i] = X.transform();
        data.v[i] = X.act_inverse(v_parent);
        data.v[i].angular[k] += qd;
        data.c[i] = cross_axis<k>(data.v[i], qd);
      });
    } else {
      data.X_P[i] = joint_transform(model, i, q);
      const Motion vJ = joint_motion(model, i, v);
      data.v[i] = data.X_P[i].act_inverse(v_parent) + vJ;
      data.c[i] = data.v[i].cross(vJ);
    }
    const SpatialInertia& I = model.inertia[i];
    if (is_massless(I)) {
      data.IA[i].setZero();
      data.pA[i] = Force::Zero();
    } else {
      I.write_matrix(data.IA[i]);
      data.pA[i] = cross(data.v[i], inertia_times(I, data.v[i]));
    }
    if (f_ext) data.pA[i] -= (*f_ext)[i];
  }
  // pass 2, leaves to root: articulated inertias and bias forces
  for (int i = model.njoints - 1; i > 0; --i) {
    if (is_hinge(model, i)) {
      const int p = model.parent[i];
      const double tau_i = tau[model.idx_v[i]];
      with_axis(model.axis_index[i],
                [&](auto axis) { articulate_hinge<axis()>(data, i, p, tau_i); });
      continue;
    }
    Matrix6 Ia;  // the inertia the parent sees, IA − U D⁻¹ Uᵀ (written by articulate*)
    Vector6 pa = data.pA[i].vector();
    switch (joint_nv(model.joint_type[i])) {
      case 0:
        Ia = data.IA[i];
        pa += Ia * data.c[i].vector();
        break;
      case 1:
        articulate_1dof(model, data, i, tau, Ia, pa);
        break;
      case 3:
        articulate<3>(model, data, i, tau, Ia, pa);
        break;
      case 6:
        articulate<6>(model, data, i, tau, Ia, pa);
        break;
    }
    const int p = model.parent[i];
    if (p > 0) {
      add_to_parent(data.X_P[i], Ia, data.IA[p]);
      data.pA[p] += data.X_P[i].act(Force::from_vector(pa));
    }
  }
  // pass 3, root to leaves: accelerations (gravity as an upward acceleration of the world)
  data.a[0] = {Vector3::Zero(), -model.gravity};
  for (int i = 1; i < model.njoints; ++i) {
    if (is_hinge(model, i)) {
      // q̈ = D⁻¹ (u − Uᵀ a'), a = a' + e_K q̈
      with_axis(model.axis_index[i], [&](auto axis) {
        constexpr int k = axis();
        Motion a =
            HingeTransform<k>::of(data.X_P[i]).act_inverse(data.a[model.parent[i]]) + data.c[i];
        const auto& U = data.U[i];
        const double Ua =
            (U(0, 0) * a.angular[0] + U(1, 0) * a.angular[1] + U(2, 0) * a.angular[2]) +
            (U(3, 0) * a.linear[0] + U(4, 0) * a.linear[1] + U(5, 0) * a.linear[2]);
        const double qdd = data.Dinv[i](0, 0) * (data.u[i][0] - Ua);
        data.ddq[model.idx_v[i]] = qdd;
        a.angular[k] += qdd;
        data.a[i] = a;
      });
      continue;
    }
    Motion a = data.X_P[i].act_inverse(data.a[model.parent[i]]) + data.c[i];
    switch (joint_nv(model.joint_type[i])) {
      case 1: {
        const double qdd = data.Dinv[i](0, 0) * (data.u[i][0] - data.U[i].col(0).dot(a.vector()));
        data.ddq[model.idx_v[i]] = qdd;
        if (model.joint_type[i] == JointType::kRevolute) {
          a.angular += model.axis[i] * qdd;
        } else {
          a.linear += model.axis[i] * qdd;
        }
        break;
      }
      case 3:
        accelerate<3>(model, data, i, a);
        break;
      case 6:
        accelerate<6>(model, data, i, a);
        break;
      default:
        break;
    }
    data.a[i] = a;
  }
  return data.ddq;
}

}  // namespace

const Eigen::VectorXd& aba(const Model& model,
                           Data& data,
                           const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v,
                           const Eigen::VectorXd& tau) {
  return aba_impl(model, data, q, v, tau, nullptr);
}

const Eigen::VectorXd& aba(const Model& model,
                           Data& data,
                           const Eigen::VectorXd& q,
                           const Eigen::VectorXd& v,
                           const Eigen::VectorXd& tau,
                           const std::vector<Force>& f_ext) {
  return aba_impl(model, data, q, v, tau, &f_ext);
}

}  // namespace core
