// Writing a spatial inertia so that it reads back bit for bit: the file holds mass, centre of
// mass c and inertia about it I_c, and the builder computes the stored spatial inertia from them
// (SpatialInertia::from_com). The plain answer (c = h / m, I_c = I_O minus the parallel-axis
// term) can miss in the last bit; then nearby doubles are searched.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <optional>
#include <vector>

#include "io/character_json_internal.hpp"

namespace io::character_json {

using namespace core;  // io reads and writes core's types

namespace {

double step_ulps(double x, int d) {
  for (int s = 0; s < std::abs(d); ++s) x = std::nextafter(x, d > 0 ? kInfinity : -kInfinity);
  return x;
}
double no_negative_zero(double x) { return x == 0 ? 0.0 : x; }

// Mirrors the builder's inertia rules: symmetric, positive semidefinite, triangle inequality.
bool plausible_inertia(const Matrix3& I) {
  const double scale = std::max(1e-12, I.cwiseAbs().maxCoeff());
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Matrix3>(I).eigenvalues();
  return e.minCoeff() >= -1e-9 * scale && e(0) + e(1) >= e(2) - 1e-6 * scale;
}

// Doubles in numeric order as integers (-0 and +0 share a key), for searching over doubles.
std::int64_t order_key(double x) {
  std::int64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b >= 0 ? b : std::numeric_limits<std::int64_t>::min() - b;
}
double from_order_key(std::int64_t k) {
  const std::int64_t b = k >= 0 ? k : std::numeric_limits<std::int64_t>::min() - k;
  double x;
  std::memcpy(&x, &b, sizeof x);
  return x;
}

struct Interval {
  double lo = 0, hi = 0;
};

// All finite doubles a with fl(a + P) == T. a -> fl(a + P) is monotone, so they form an interval;
// a solution is looked for next to T - P, then both ends are found by galloping and bisection.
std::optional<Interval> sum_preimage(double P, double T) {
  auto ok = [&](std::int64_t k) { return from_order_key(k) + P == T; };
  const double a0 = T - P;
  std::optional<std::int64_t> seed;
  for (int d : {0, -1, 1, -2, 2, -3, 3}) {
    const double a = step_ulps(a0, d);
    if (std::isfinite(a) && ok(order_key(a))) {
      seed = order_key(a);
      break;
    }
  }
  if (!seed) return std::nullopt;
  const std::int64_t kmin = order_key(-std::numeric_limits<double>::max());
  const std::int64_t kmax = order_key(std::numeric_limits<double>::max());
  auto edge = [&](bool up) {
    std::int64_t good = *seed, bad = 0;
    const std::int64_t limit = up ? kmax : kmin;
    for (std::uint64_t step = 1;; step *= 2) {
      const std::uint64_t room =
          up ? static_cast<std::uint64_t>(limit) - static_cast<std::uint64_t>(good)
             : static_cast<std::uint64_t>(good) - static_cast<std::uint64_t>(limit);
      const std::int64_t next = room <= step ? limit
                                             : (up ? good + static_cast<std::int64_t>(step)
                                                   : good - static_cast<std::int64_t>(step));
      if (!ok(next)) {
        bad = next;
        break;
      }
      good = next;
      if (next == limit) return good;
    }
    for (;;) {
      const std::int64_t mid = std::midpoint(good, bad);
      if (mid == good || mid == bad) return good;
      (ok(mid) ? good : bad) = mid;
    }
  };
  return Interval{from_order_key(edge(false)), from_order_key(edge(true))};
}

using Box = std::array<std::array<Interval, 3>, 3>;

// G clamped entry by entry into the box of inertias that reproduce I_O.
Matrix3 into_box(const Matrix3& G, const Box& box) {
  Matrix3 I;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      I(i, j) = no_negative_zero(std::clamp(G(i, j), box[i][j].lo, box[i][j].hi));
    }
  }
  return I;
}

// Inertias to try for one centre of mass: the plain answer, the same without products of
// inertia, and both with equal principal moments d, d taken from each moment in the box and
// large enough to dominate the products (Gershgorin: the moments lie in [d - r, d + r], so
// d >= 3r satisfies the triangle inequality).
std::vector<Matrix3> inertia_guesses(const Matrix3& G_plain, const Box& box) {
  Matrix3 G_diagonal = Matrix3::Zero();
  G_diagonal.diagonal() = G_plain.diagonal();
  std::vector<Matrix3> guesses{G_plain, G_diagonal};
  for (const Matrix3& base : {G_diagonal, G_plain}) {
    const Matrix3 B = into_box(base, box);
    double r = 0;
    for (int i = 0; i < 3; ++i) r = std::max(r, B.row(i).cwiseAbs().sum() - std::abs(B(i, i)));
    for (double d : {B(0, 0), B(1, 1), B(2, 2), 4 * r, std::max(B.diagonal().maxCoeff(), 4 * r)}) {
      Matrix3 G = base;
      G.diagonal().setConstant(d);
      guesses.push_back(G);
    }
  }
  return guesses;
}

// For one centre of mass c: the box of all I_c with fl(I_c + P) = I_O entry by entry (P the
// parallel-axis term of c), and the first plausible guess inside it that reproduces T. An exact
// but implausible one is kept in `exact_only` as a fallback.
std::optional<InertiaForm> search_at(const SpatialInertia& T,
                                     const Vector3& com,
                                     std::optional<InertiaForm>& exact_only) {
  InertiaForm f;
  f.com = com;
  const Matrix3 P = SpatialInertia::from_com(T.mass, f.com, Matrix3::Zero()).I_O;
  Box box;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const auto iv = sum_preimage(P(i, j), T.I_O(i, j));
      if (!iv) return std::nullopt;
      box[i][j] = *iv;
    }
  }
  for (const Matrix3& G : inertia_guesses(T.I_O - P, box)) {
    f.I = into_box(G, box);
    if (!(SpatialInertia::from_com(T.mass, f.com, f.I) == T)) continue;
    if (plausible_inertia(f.I)) return f;
    if (!exact_only) exact_only = f;
  }
  return std::nullopt;
}

}  // namespace

// The plain answer can miss in the last bit, and where the parallel-axis term dwarfs the inertia
// it leaves rounding residue the builder rejects (a point mass with a slightly negative moment).
// Then each c with fl(m c_k) = h_k near h / m is tried (search_at).
InertiaForm inertia_form(const SpatialInertia& T) {
  InertiaForm plain;
  if (!(T.mass > 0)) {
    plain.I = T.I_O.unaryExpr(&no_negative_zero);  // I_O = I_c exactly when m = 0
    return plain;
  }
  plain.com = T.com().unaryExpr(&no_negative_zero);
  plain.I = T.inertia_about_com().unaryExpr(&no_negative_zero);
  if (SpatialInertia::from_com(T.mass, plain.com, plain.I) == T && plausible_inertia(plain.I)) {
    return plain;
  }

  std::array<std::vector<double>, 3> candidates;
  for (int k = 0; k < 3; ++k) {
    const double c = T.h[k] / T.mass;
    for (int d : {0, -1, 1, -2, 2, -3, 3, -4, 4}) {
      const double x = no_negative_zero(step_ulps(c, d));
      if (T.mass * x == T.h[k]) candidates[k].push_back(x);
    }
    if (candidates[k].empty()) return plain;
  }
  std::optional<InertiaForm> exact_only;
  for (double cx : candidates[0]) {
    for (double cy : candidates[1]) {
      for (double cz : candidates[2]) {
        if (auto f = search_at(T, Vector3(cx, cy, cz), exact_only)) return *f;
      }
    }
  }
  return exact_only ? *exact_only : plain;
}

}  // namespace io::character_json
