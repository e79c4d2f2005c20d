#include "core/crba.hpp"

#include <algorithm>
#include <type_traits>

#include "core/hinge.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"

namespace core {

namespace {

// out[c] = F_cᵀ s for c in first..end-1, F_c the c-th row of the nv-row column-major F. The
// output is declared apart from F and s (restrict), so the loop runs two entries at a time
// without the run-time overlap checks it would need otherwise (the runs are short: a limb).
inline void column_times_motion(const double* __restrict f,
                                Eigen::Index nv,
                                const double* __restrict s,
                                int first,
                                int end,
                                double* __restrict out) {
  for (int c = first; c < end; ++c) {
    out[c] = (f[c] * s[0] + f[nv + c] * s[1] + f[2 * nv + c] * s[2]) +
             (f[3 * nv + c] * s[3] + f[4 * nv + c] * s[4] + f[5 * nv + c] * s[5]);
  }
}

// The six columns of a free joint at coordinates a..a+5, entries first..end-1. Its axes are the
// body's (R, p): turning about R_k has S = (R_k, p × R_k) and moving along it S = (0, R_k), so
// with F_c = (n, f) at the world origin, H(c, a+k) = R_kᵀ (n − p × f) (the force moved to the
// body's origin) and H(c, a+3+k) = R_kᵀ f: 42 flops per row instead of 6 dot products of 6.
// One pointer per column, each restrict, so the loop runs two rows at a time.
inline void free_joint_columns(const double* __restrict f,
                               Eigen::Index nv,
                               const double (&R)[3][3],  // R[k]: the body's axis k in the world
                               const double (&p)[3],
                               int first,
                               int end,
                               double* __restrict turn_x,
                               double* __restrict turn_y,
                               double* __restrict turn_z,
                               double* __restrict move_x,
                               double* __restrict move_y,
                               double* __restrict move_z) {
  for (int c = first; c < end; ++c) {
    const double nx = f[c], ny = f[nv + c], nz = f[2 * nv + c];
    const double fx = f[3 * nv + c], fy = f[4 * nv + c], fz = f[5 * nv + c];
    // n − p × f
    const double mx = nx - (p[1] * fz - p[2] * fy), my = ny - (p[2] * fx - p[0] * fz),
                 mz = nz - (p[0] * fy - p[1] * fx);
    turn_x[c] = R[0][0] * mx + R[0][1] * my + R[0][2] * mz;
    turn_y[c] = R[1][0] * mx + R[1][1] * my + R[1][2] * mz;
    turn_z[c] = R[2][0] * mx + R[2][1] * my + R[2][2] * mz;
    move_x[c] = R[0][0] * fx + R[0][1] * fy + R[0][2] * fz;
    move_y[c] = R[1][0] * fx + R[1][1] * fy + R[1][2] * fz;
    move_z[c] = R[2][0] * fx + R[2][1] * fy + R[2][2] * fz;
  }
}

// Columns a..a+5 of H (column-major m, nv × nv), rows a..end-1, for the free joint whose body
// sits at X in the world: its six columns at once, then the 6×6 block's upper triangle from its
// lower one (computed both ways they differ by rounding, and H must be exactly symmetric), then,
// when mirror_rows, rows a..a+5 past the block, each row's six entries side by side.
void fill_free_joint_block(const double* f0,
                           Eigen::Index nv,
                           const Transform& X,
                           int a,
                           int end,
                           bool mirror_rows,
                           double* m) {
  double R[3][3], p[3];
  for (int k = 0; k < 3; ++k) {
    for (int r = 0; r < 3; ++r) R[k][r] = X.R(r, k);
    p[k] = X.p[k];
  }
  double* const column = m + a * nv;
  free_joint_columns(f0, nv, R, p, a, end, column, column + nv, column + 2 * nv, column + 3 * nv,
                     column + 4 * nv, column + 5 * nv);
  for (int c = a + 1; c < a + 6; ++c) {
    for (int k = 0; k < c - a; ++k) m[c * nv + a + k] = column[k * nv + c];
  }
  if (!mirror_rows) return;
  for (int c = a + 6; c < end; ++c) {
    for (int k = 0; k < 6; ++k) m[c * nv + a + k] = column[k * nv + c];
  }
}

}  // namespace

const Eigen::MatrixXd& crba(const Model& model, Data& data, const Eigen::VectorXd& q) {
  // Everything in world axes at the world origin (RBDA §6.2 in a single frame): the composite
  // inertias then add without transforms, and H_ac = S_aᵀ Ic_c S_c for a an ancestor of c (or an
  // earlier coordinate of c's joint) is a dot product with S_a instead of a force transform per
  // ancestor.
  forward_kinematics(model, q, data.X_P, data.crba_X_W);
  compute_joint_jacobians(model, data.crba_X_W, data.crba_S);
  const Matrix6X& S = data.crba_S;
  // composite inertias, from the leaves up
  for (int i = 1; i < model.njoints; ++i) {
    const SpatialInertia& I = model.inertia[i];
    data.Ic[i] = is_massless(I) ? SpatialInertia::Zero() : I.transformed(data.crba_X_W[i]);
  }
  for (int i = model.njoints - 1; i > 0; --i) {
    const int p = model.parent[i];
    if (p > 0) data.Ic[p] += data.Ic[i];
  }
  // F_c = Ic S_c: the force that accelerates c's subtree along coordinate c (a row of crba_F)
  Eigen::MatrixXd& F = data.crba_F;
  for (int c = 0; c < model.nv; ++c) {
    const double* s_c = S.data() + 6 * c;
    const Force f = inertia_times(data.Ic[model.joint_of_v[c]],
                                  {{s_c[0], s_c[1], s_c[2]}, {s_c[3], s_c[4], s_c[5]}});
    F.row(c) << f.angular.transpose(), f.linear.transpose();
  }
  // Column a of H below the diagonal: the coordinates hanging from a are a..end-1 (the rest of
  // its joint, then its subtree, contiguous in depth-first order), so H(c, a) = F_cᵀ S_a for all
  // of them is one product of a block of crba_F with S_a over contiguous memory.
  Eigen::MatrixXd& M = data.M;
  const Eigen::Index nv = model.nv;
  const double* f0 = F.data();  // column k of crba_F starts at f0 + k nv
  double* const m = M.data();
  // The upper triangle mirrors the lower. While H fits in the L1 cache (nv ≤ 64: 32 KiB) each
  // column's entries are mirrored as they are made, touching only the tree's ancestor pairs;
  // beyond, row-wise stores a whole column apart miss the cache, and a tiled copy of the
  // triangle is 5x faster on a 512-link chain.
  const bool mirror_inline = nv <= 64;
  for (int a = 0; a < model.nv; ++a) {
    const int j = model.joint_of_v[a];
    const int end =
        model.subtree_end[j] < model.njoints ? model.idx_v[model.subtree_end[j]] : model.nv;
    double* const column = m + a * nv;
    if (model.joint_type[j] == JointType::kFree) {
      fill_free_joint_block(f0, nv, data.crba_X_W[j], a, end, mirror_inline, m);
      a += 5;
      continue;
    }
    column_times_motion(f0, nv, S.data() + 6 * a, a, end, column);
    if (mirror_inline) {
#pragma GCC unroll 4
      for (int c = a + 1; c < end; ++c) m[c * nv + a] = column[c];
    }
  }
  if (mirror_inline) return M;
  // tile by tile, so both sides stay in cache (entries off the ancestor pairs are zero on both)
  constexpr Eigen::Index kTile = 8;
  for (Eigen::Index j0 = 0; j0 < nv; j0 += kTile) {
    const Eigen::Index j1 = std::min(j0 + kTile, nv);
    for (Eigen::Index i0 = j0; i0 < nv; i0 += kTile) {
      const Eigen::Index i1 = std::min(i0 + kTile, nv);
      for (Eigen::Index i = i0; i < i1; ++i) {
        for (Eigen::Index j = j0; j < std::min(j1, i); ++j) m[i * nv + j] = m[j * nv + i];
      }
    }
  }
  return M;
}

void ltdl_factorize(const Model& model, Eigen::Ref<Eigen::MatrixXd> H) {
  // The elimination runs on the transposed (upper) positions, H(j, i) standing for H(i, j) with j
  // an ancestor of i: walking the ancestors then reads down a column, which is contiguous
  // wherever coordinates are numbered consecutively (limbs, chains), instead of across a row (a
  // cache miss per entry once the matrix outgrows the cache: 2x on a 512-link chain). The lower
  // triangle goes up first and L comes back down after, as documented.
  const std::vector<int>& lambda = model.parent_v;
  double* const base = H.data();
  const Eigen::Index stride = H.outerStride();
  // H(j, k) and H(k, j) for k's ancestors j, one copied onto the other (the direction fixed at
  // compile time: this is on the mass matrix's path)
  const auto copy_pairs = [&](auto lower_to_upper) {
    for (int k = 1; k < model.nv; ++k) {
      if (lambda[k] < 0) continue;
      double* const Hk = base + k * stride;  // Hk[j] = H(j, k): upper
      for_each_ancestor_run(model, lambda[k], [&](int c, int n) {
        for (int j = c; j < c + n; ++j) {
          double& lower = base[j * stride + k];  // H(k, j)
          if constexpr (decltype(lower_to_upper)::value) {
            Hk[j] = lower;
          } else {
            lower = Hk[j];
          }
        }
      });
    }
  };
  copy_pairs(std::true_type{});
  ltdl_factorize_upper(model, H);
  copy_pairs(std::false_type{});
}

void ltdl_factorize_upper(const Model& model, Eigen::Ref<Eigen::MatrixXd> H) {
  // LTDL (RBDA Table 6.3): eliminate from the leaves up, touching only ancestor pairs, each
  // column k holding H(j, k) for the ancestors j of k. The runs are short (a limb), so they are
  // plain loops: a vectorized segment's set-up costs more than the run.
  const std::vector<int>& lambda = model.parent_v;
  double* const base = H.data();
  const Eigen::Index stride = H.outerStride();
  for (int k = model.nv - 1; k >= 0; --k) {
    double* const Hk = base + k * stride;  // Hk[j] = H(j, k) for the ancestors j of k
    const double inv_dk = 1.0 / Hk[k];
    for (int i = lambda[k]; i >= 0; i = lambda[i]) {
      // H(j, i) −= a H(j, k) for i and its ancestors j, then H(i, k) = a
      const double a = Hk[i] * inv_dk;
      double* const Hi = base + i * stride;
      for_each_ancestor_run(model, i, [&](int c, int n) {
        for (int j = c; j < c + n; ++j) Hi[j] -= a * Hk[j];
      });
      Hk[i] = a;
    }
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
    for_each_ancestor_run(model, model.parent_v[k], [&](int c, int n) {
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
    for_each_ancestor_run(model, model.parent_v[k], [&](int c, int n) {
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

void solve_mass_matrix_lt_on_path(const Model& model,
                                  const Data& data,
                                  int last,
                                  Eigen::Ref<Eigen::MatrixXd> X) {
  // ltdl_solve_lt restricted to the path: x_k is zero off it, and k only updates its ancestors,
  // which are on it too. Coordinates go leaf to root, as there.
  const Eigen::Index w = X.cols(), x_stride = X.outerStride();
  double* const x = X.data();
  const double* const L = data.LTDL.data();
  const Eigen::Index l_stride = data.LTDL.outerStride();
  for_each_ancestor_run(model, last, [&](int start, int n) {
    for (int k = start + n - 1; k >= start; --k) {
      if (model.parent_v[k] < 0) continue;
      const double* const Lk = L + k * l_stride;  // Lk[j] = L(k, j) for the ancestors j of k
      for (Eigen::Index t = 0; t < w; ++t) {
        const double xk = x[t * x_stride + k];
        if (xk == 0) continue;
        double* const xt = x + t * x_stride;
        for_each_ancestor_run(model, model.parent_v[k], [&](int c, int m) {
          for (int j = c; j < c + m; ++j) xt[j] -= xk * Lk[j];
        });
      }
    }
  });
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
