#include "core/crba.hpp"

#include "core/hinge.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"

namespace core {

namespace {

// f(first, count) for each run of consecutive coordinates among k and its ancestors, from k up.
// Walking runs instead of one parent at a time keeps the loads independent (a limb is one run),
// so the updates stream through contiguous memory instead of waiting on each parent's index.
template <typename F>
inline void for_each_run_from(const Model& model, int k, F&& f) {
  const int* start = model.chain_start_v.data();
  const int* parent = model.parent_v.data();
  for (int j = k; j >= 0;) {
    const int c = start[j];
    f(c, j - c + 1);
    j = parent[c];
  }
}

}  // namespace

const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q) {
  // Everything in world axes at the world origin (RBDA §6.2 in a single frame): the composite
  // inertias then add without transforms, and H_ij = S_jᵀ Ic_i S_i for j an ancestor of i is a
  // dot product with S_j instead of a force transform per ancestor.
  forward_kinematics(model, q, data.X_P, data.crba_X_W);
  compute_joint_jacobians(model, data.crba_X_W, data.crba_S);
  const Matrix6X& S = data.crba_S;
  for (int i = 1; i < model.njoints; ++i) {
    const SpatialInertia& I = model.inertia[i];
    data.Ic[i] = is_massless(I) ? SpatialInertia::Zero() : I.transformed(data.crba_X_W[i]);
  }
  // backward pass: fill the row and column of each coordinate, then pass the composite up
  Eigen::MatrixXd& M = data.M;
  const std::size_t nv = static_cast<std::size_t>(model.nv);
  for (int i = model.njoints - 1; i > 0; --i) {
    const SpatialInertia& Ic = data.Ic[i];
    const int c0 = model.idx_v[i];
    const int c1 = c0 + joint_nv(model.joint_type[i]);
    for (int c = c0; c < c1; ++c) {
      // F = Ic S_c: the force that accelerates the subtree along coordinate c
      const double* s_c = S.data() + 6 * c;
      const Force F = inertia_times(Ic, {{s_c[0], s_c[1], s_c[2]}, {s_c[3], s_c[4], s_c[5]}});
      const double f[6] = {F.angular[0], F.angular[1], F.angular[2],
                           F.linear[0],  F.linear[1],  F.linear[2]};
      // H(c, a) = S_aᵀ F for c and every coordinate a above it (its joint's earlier ones too),
      // run by run: the columns S_a of a run are consecutive 6-vectors, H(a, c) is consecutive
      // down column c, and H(c, a) steps by one column
      double* const M_data = M.data();
      for_each_run_from(model, c, [&](int first, int n) {
        const double* s_a = S.data() + 6 * first;
        double* column_c = M_data + c * nv + first;  // M(a, c)
        double* row_c = M_data + first * nv + c;     // M(c, a)
        for (int k = 0; k < n; ++k, s_a += 6, row_c += nv) {
          const double h = (s_a[0] * f[0] + s_a[1] * f[1] + s_a[2] * f[2]) +
                           (s_a[3] * f[3] + s_a[4] * f[4] + s_a[5] * f[5]);
          column_c[k] = h;
          *row_c = h;
        }
      });
    }
    const int p = model.parent[i];
    if (p > 0) data.Ic[p] += Ic;
  }
  return M;
}

void ltdl_factorize(const Model& model, Eigen::Ref<Eigen::MatrixXd> H) {
  const std::vector<int>& lambda = model.parent_v;
  // LTDL (RBDA Table 6.3): eliminate from the leaves up, touching only ancestor pairs. The
  // elimination runs on the transposed (upper) positions, H(j, i) standing for H(i, j) with j an
  // ancestor of i: walking the ancestors then reads down a column, which is contiguous wherever
  // coordinates are numbered consecutively (limbs, chains), instead of across a row (a cache miss
  // per entry once the matrix outgrows the cache: 2x on a 512-link chain). Same operations,
  // same results; L goes back to the lower triangle as documented. The runs are short (a limb),
  // so they are plain loops: a vectorized segment's set-up costs more than the run.
  double* const base = H.data();
  const Eigen::Index stride = H.outerStride();
  const auto column = [&](int j) { return base + j * stride; };
  for (int k = 1; k < model.nv; ++k) {
    if (lambda[k] < 0) continue;
    double* Hk = column(k);
    for_each_run_from(model, lambda[k], [&](int c, int n) {
      for (int j = c; j < c + n; ++j) Hk[j] = column(j)[k];
    });
  }
  for (int k = model.nv - 1; k >= 0; --k) {
    double* const Hk = column(k);  // Hk[j] = H(j, k) for the ancestors j of k
    const double inv_dk = 1.0 / Hk[k];
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      // H(j, i) −= a H(j, k) for i and its ancestors j, then H(i, k) = a
      const double a = Hk[i] * inv_dk;
      double* const Hi = column(i);
      for_each_run_from(model, i, [&](int c, int n) {
        for (int j = c; j < c + n; ++j) Hi[j] -= a * Hk[j];
      });
      Hk[i] = a;
    }
    if (lambda[k] < 0) continue;
    for_each_run_from(model, lambda[k], [&](int c, int n) {
      for (int j = c; j < c + n; ++j) column(j)[k] = Hk[j];
    });
  }
}

// L(k, i) for the ancestors i of k sits in both triangles after ltdl_factorize; the solves read it
// down column k (contiguous) as H(i, k).
void ltdl_solve_lt(const Model& model,
                   const Eigen::Ref<const Eigen::MatrixXd>& L,
                   Eigen::Ref<Eigen::VectorXd> x) {
  double* const xs = x.data();
  for (int k = model.nv - 1; k >= 0; --k) {
    const double xk = xs[k];
    if (xk == 0 || model.parent_v[k] < 0) continue;
    const double* Lk = L.data() + k * L.outerStride();
    for_each_run_from(model, model.parent_v[k], [&](int c, int n) {
      for (int j = c; j < c + n; ++j) xs[j] -= xk * Lk[j];
    });
  }
}

void ltdl_solve_l(const Model& model,
                  const Eigen::Ref<const Eigen::MatrixXd>& L,
                  Eigen::Ref<Eigen::VectorXd> x) {
  double* const xs = x.data();
  for (int k = 0; k < model.nv; ++k) {
    if (model.parent_v[k] < 0) continue;
    const double* Lk = L.data() + k * L.outerStride();
    double sum = 0;
    for_each_run_from(model, model.parent_v[k], [&](int c, int n) {
      for (int j = c; j < c + n; ++j) sum += Lk[j] * xs[j];
    });
    xs[k] -= sum;
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
