#include "ik/sr_inverse.hpp"

#include <algorithm>
#include <cmath>

namespace ik {

const char* to_string(DampingSchedule s) {
  switch (s) {
    case DampingSchedule::kConstant:
      return "constant";
    case DampingSchedule::kManipulability:
      return "manipulability";
    case DampingSchedule::kResidual:
      return "residual";
  }
  return "?";
}

std::optional<DampingSchedule> damping_schedule_from_string(std::string_view s) {
  for (DampingSchedule d :
       {DampingSchedule::kConstant, DampingSchedule::kManipulability, DampingSchedule::kResidual}) {
    if (s == to_string(d)) return d;
  }
  return std::nullopt;
}

SrInverse::Result SrInverse::solve(const Eigen::Ref<const Eigen::MatrixXd>& A,
                                   const Eigen::Ref<const Eigen::VectorXd>& b,
                                   double damping,
                                   DampingSchedule schedule,
                                   double threshold,
                                   Eigen::Ref<Eigen::VectorXd> x) {
  const Eigen::Index m = A.rows(), n = A.cols();
  Result result;
  if (m == 0) {
    x.setZero();
    return result;
  }
  // Gram matrix of the smaller side: A Aᵀ (m ≤ n) or Aᵀ A (m > n)
  const bool wide = m <= n;
  const Eigen::Index r = wide ? m : n;
  if (gram_.rows() < r) gram_.resize(r, r);
  if (rhs_.size() < r) rhs_.resize(r);
  auto G = gram_.topLeftCorner(r, r);
  G.setZero();
  if (wide) {
    G.selfadjointView<Eigen::Lower>().rankUpdate(A);
  } else {
    G.selfadjointView<Eigen::Lower>().rankUpdate(A.transpose());
  }
  double k = damping;
  if (schedule == DampingSchedule::kResidual) {
    k = std::max(1e-12, damping * std::min(1.0, b.squaredNorm() / (threshold * threshold)));
  } else if (schedule == DampingSchedule::kManipulability) {
    // w from a lightly regularized factorization; damping grows as w falls below w0
    // w from the Cholesky diagonal of a copy (lower triangle only), damping grows below w0
    constexpr double kFloor = 1e-12;
    auto F = rhs_.head(r);  // reuse as scratch for the diagonal
    {
      Eigen::MatrixXd& scratch = scratch_;
      if (scratch.rows() < r) scratch.resize(r, r);
      auto C = scratch.topLeftCorner(r, r);
      C.triangularView<Eigen::Lower>() = G;
      C.diagonal().array() += kFloor;
      Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(C);
      F = C.diagonal();
    }
    double log_det = 0;
    for (Eigen::Index i = 0; i < r; ++i) log_det += std::log(F[i]);
    result.manipulability = std::exp(log_det / static_cast<double>(r));
    const double w = result.manipulability;
    k = w < threshold ? damping * (1.0 - w / threshold) * (1.0 - w / threshold) : 0.0;
    k = std::max(k, kFloor);
  }
  G.diagonal().array() += k;
  result.damping = k;
  // in-place Cholesky of the corner: no allocation
  Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(G);
  if (wide) {
    // x = Aᵀ (A Aᵀ + k E)⁻¹ b
    auto y = rhs_.head(r);
    y = b;
    llt.solveInPlace(y);
    x.noalias() = A.transpose() * y;
  } else {
    // x = (Aᵀ A + k E)⁻¹ Aᵀ b
    x.noalias() = A.transpose() * b;
    llt.solveInPlace(x);
  }
  return result;
}

}  // namespace ik
