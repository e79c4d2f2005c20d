// y += a x over short arrays, the inner loop of the tree-sparse factorization and solves.
#pragma once

namespace core {

/// y[0 … n) += a x[0 … n) for two arrays that do not overlap. __restrict__ says so to the
/// compiler, which then vectorizes the loop without the overlap check it would otherwise add
/// before it: that check costs more than the short updates themselves.
inline void add_scaled(double* __restrict__ y, const double* __restrict__ x, double a, int n) {
  for (int j = 0; j < n; ++j) y[j] += a * x[j];
}

}  // namespace core
