#pragma once
// Checks the solvers' settings validators share (ik/solver.cpp, ik/acceleration_solver.cpp).
#include <cmath>

namespace ik {

/// True for a finite number above zero: gains, time steps, error bounds.
inline bool positive_finite(double x) { return std::isfinite(x) && x > 0; }

}  // namespace ik
