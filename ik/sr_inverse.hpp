// Damped least squares: the singularity-robust (SR) inverse of Yamane eq. 8.7.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <optional>
#include <string_view>

namespace ik {

/// How the SR damping k is chosen.
enum class DampingSchedule {
  kConstant,        // k fixed
  kManipulability,  // k = k0 (1 − w/w0)² below w0 (Nakamura & Hanafusa 1986), else a floor
  kResidual,        // k = k0 min(1, |r|²/v²): grows with the squared residual (Sugihara 2011)
};

const char* to_string(DampingSchedule s);  // "constant", "manipulability", "residual"
std::optional<DampingSchedule> damping_schedule_from_string(std::string_view s);

/// Solves min |b − A x|² + k |x|² for x, i.e. x = A* b with the SR inverse
/// A* = Aᵀ(A Aᵀ + k E)⁻¹ (m ≤ n) or (Aᵀ A + k E)⁻¹ Aᵀ (m > n), by Cholesky of the smaller Gram
/// matrix (Yamane eq. 8.7, digest §2.1). Every singular value's gain is bounded by 1/(2√k).
/// Row and column weights are applied by the caller as scalings of A's rows and columns.
/// The workspace grows to the largest problem seen and never allocates afterwards.
class SrInverse {
 public:
  struct Result {
    double damping = 0;         // the k actually used
    double manipulability = 0;  // w = det(Gram)^(1/2r), geometric mean of singular values
  };

  /// x (n) = A* b; A is m x n. With kManipulability, k0 = damping and w0 = threshold; with
  /// kResidual, k = damping min(1, |b|²/threshold²).
  Result solve(const Eigen::Ref<const Eigen::MatrixXd>& A,
               const Eigen::Ref<const Eigen::VectorXd>& b,
               double damping,
               DampingSchedule schedule,
               double threshold,
               Eigen::Ref<Eigen::VectorXd> x);

 private:
  // capacity grows to the largest problem; smaller problems use the top-left corner
  Eigen::MatrixXd gram_;
  Eigen::VectorXd rhs_;
  Eigen::MatrixXd scratch_;
};

}  // namespace ik
