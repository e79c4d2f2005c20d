// Euler angles of BVH rotation channels: rotation orders, the matrix of three elementary rotations
// in file order (intrinsic), and its decomposition with unwrapping across frames.
// docs: ../shared/reference/ecosystem.md §1.3.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>

#include "io/core_names.hpp"

namespace io {

/// Three distinct axes (0 = X, 1 = Y, 2 = Z) in file order: "ZXY" is {2, 0, 1}, R = Rz Rx Ry.
using BvhRotationOrder = std::array<int, 3>;
/// "ZXY", "zxy", ... → the order; empty for anything but a permutation of X, Y, Z.
std::optional<BvhRotationOrder> parse_rotation_order(std::string_view s);
std::string to_string(const BvhRotationOrder& order);

/// R_axis(θ), the rotation by θ radians about X (0), Y (1) or Z (2).
inline Matrix3 elementary_rotation(int axis, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  Matrix3 R = Matrix3::Identity();
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  R(a, a) = c;
  R(a, b) = -s;
  R(b, a) = s;
  R(b, b) = c;
  return R;
}

/// R = R_a0(angles[0]) R_a1(angles[1]) R_a2(angles[2]) (intrinsic, radians).
Matrix3 euler_to_matrix(const BvhRotationOrder& order, const Vector3& angles);
/// Angles (radians) with euler_to_matrix(order, angles) == R. Without `previous`: the middle angle
/// in [-π/2, π/2], the others in (-π, π]. With `previous`: of the two equivalent triples, each
/// shifted by multiples of 2π, the one closest to `previous` (Euler unwrapping). At the singular
/// middle angle ±π/2 the first angle is kept from `previous` (0 without).
Vector3 matrix_to_euler(const Matrix3& R,
                        const BvhRotationOrder& order,
                        const Vector3* previous = nullptr);

}  // namespace io
