#include "io/bvh_euler.hpp"

#include <numbers>

#include "io/bvh_text.hpp"

namespace io {

namespace {

// angle + 2πn, the n that brings it closest to reference
double wrap_near(double angle, double reference) {
  const double two_pi = 2 * std::numbers::pi;
  return angle + two_pi * std::round((reference - angle) / two_pi);
}

}  // namespace

std::optional<BvhRotationOrder> parse_rotation_order(std::string_view s) {
  if (s.size() != 3) return std::nullopt;
  BvhRotationOrder order{};
  bool used[3] = {false, false, false};
  for (int k = 0; k < 3; ++k) {
    const char c = bvh_detail::lower(s[k]);
    if (c < 'x' || c > 'z') return std::nullopt;
    const int a = c - 'x';
    if (used[a]) return std::nullopt;
    used[a] = true;
    order[k] = a;
  }
  return order;
}

std::string to_string(const BvhRotationOrder& order) {
  std::string s;
  for (int a : order) s += static_cast<char>('X' + a);
  return s;
}

Matrix3 euler_to_matrix(const BvhRotationOrder& order, const Vector3& angles) {
  return elementary_rotation(order[0], angles[0]) * elementary_rotation(order[1], angles[1]) *
         elementary_rotation(order[2], angles[2]);
}

Vector3 matrix_to_euler(const Matrix3& R, const BvhRotationOrder& order, const Vector3* previous) {
  const int i = order[0], j = order[1], k = order[2];
  // parity of the permutation (i, j, k): +1 for XYZ, YZX, ZXY
  const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
  // R = R_i(a) R_j(b) R_k(c): R(i, k) = s sin b, and the other entries of row i and column k
  // carry cos b (see ecosystem.md §1.3 for ZXY)
  const double cos_b = std::hypot(R(i, i), R(i, j));
  const double b = std::atan2(s * R(i, k), cos_b);
  double a = 0;
  if (std::hypot(R(j, k), R(k, k)) > 1e-12) {
    a = std::atan2(-s * R(j, k), R(k, k));
  } else if (previous) {
    a = (*previous)[0];  // gimbal lock: only a ± c is defined; keep a continuous
  }
  // c from what is left: R_k(c) = R_j(b)ᵀ R_i(a)ᵀ R, exact even near the singularity
  const Matrix3 M = (elementary_rotation(i, a) * elementary_rotation(j, b)).transpose() * R;
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  const double c = std::atan2(M(k2, k1), M(k1, k1));
  Vector3 first(a, b, c);
  if (!previous) return first;
  // the equivalent triple (a + π, π - b, c + π); each unwrapped to the previous frame
  const double pi = std::numbers::pi;
  Vector3 second(a + pi, pi - b, c + pi);
  for (int n = 0; n < 3; ++n) {
    first[n] = wrap_near(first[n], (*previous)[n]);
    second[n] = wrap_near(second[n], (*previous)[n]);
  }
  return (first - *previous).cwiseAbs().sum() <= (second - *previous).cwiseAbs().sum() ? first
                                                                                       : second;
}

}  // namespace io
