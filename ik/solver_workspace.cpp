#include "ik/solver_workspace.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>

#include "core/configuration.hpp"

namespace ik {

namespace {

// rows a range block of joint i contributes
int range_block_rows(const core::Model& m, int i) {
  switch (m.joint_type[i]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      return 1;
    case core::JointType::kSpherical:
      return m.spherical_range[i].empty() ? 0 : 3;
    default:
      return 0;
  }
}

}  // namespace

DampedGramInverse::DampedGramInverse(int rows)
    : vectors(rows, rows),
      sigma2(rows),
      subdiagonal(std::max(rows - 1, 0)),
      householder(std::max(rows - 1, 0)),
      reflector_scratch(rows),
      gain(rows),
      scaled_vectors(rows, rows),
      inverse(rows, rows) {}

void DampedGramInverse::decompose(const Eigen::Ref<const Eigen::MatrixXd>& G) {
  constexpr int kEigenIterations = 30;  // per eigenvalue, as SelfAdjointEigenSolver
  const Eigen::Index m = G.rows();
  Eigen::MatrixXd& V = vectors;
  // map the coefficients to [−1, 1] against overflow and underflow
  V = G.triangularView<Eigen::Lower>();
  double scale = V.cwiseAbs().maxCoeff();
  if (scale == 0) scale = 1;
  V.triangularView<Eigen::Lower>() /= scale;
  // Q T Qᵀ: T on the diagonals, Q as Householder reflectors below them, then Q itself in V
  Eigen::internal::tridiagonalization_inplace(V, householder);
  sigma2 = V.diagonal();
  subdiagonal = V.diagonal<-1>();
  Eigen::HouseholderSequence<Eigen::MatrixXd, Eigen::VectorXd>(V, householder)
      .setLength(m - 1)
      .setShift(1)
      .evalTo(V, reflector_scratch);
  // implicit symmetric QR on T, rotating Q into V; eigenvalues ascending
  Eigen::internal::computeFromTridiagonal_impl(sigma2, subdiagonal, kEigenIterations, true, V);
  sigma2 *= scale;
}

Workspace::Workspace(const core::Model& model)
    : joint_scale(Eigen::VectorXd::Ones(model.nv)),
      x(Eigen::VectorXd::Zero(model.nv)),
      x_drag(Eigen::VectorXd::Zero(model.nv)),
      x_range(Eigen::VectorXd::Zero(model.nv)),
      x_pin(Eigen::VectorXd::Zero(model.nv)),
      joint_velocity(Eigen::VectorXd::Zero(model.nv)),
      range_flagged(model.njoints, 0),
      normal_matrix(model),
      pivot_inverse(model.nv),
      path_rows(6, model.nv),
      manipulability_pivots(model),
      normal_rhs(model.nv),
      half_solved_rhs(model.nv) {
  // level 2 never has more rows than every joint's range block at once
  int range_capacity = 0;
  for (int i = 1; i < model.njoints; ++i) range_capacity += range_block_rows(model, i);
  range_blocks.reserve(model.njoints);
  range_coordinate.resize(range_capacity);
  range_velocity.resize(range_capacity);
  range_projected.resize(range_capacity, model.nv);
  range_gram.resize(range_capacity, range_capacity);
  range_multipliers.resize(range_capacity);
  // the velocity coordinates on each link's path to the root, ascending (a link task's row can
  // only touch these, so level 3's normal matrix has the tree's sparsity)
  link_path.resize(model.njoints);
  for (int i = 1; i < model.njoints; ++i) {
    for (int j = i; j > 0; j = model.parent[j]) {
      for (int d = core::joint_nv(model.joint_type[j]) - 1; d >= 0; --d) {
        link_path[i].push_back(model.idx_v[j] + d);
      }
    }
    std::reverse(link_path[i].begin(), link_path[i].end());
  }
}

void Workspace::reserve(int top_rows, int lower_rows) {
  const Eigen::Index nv = joint_scale.size();
  if (drag_jacobian.rows() < top_rows) {
    const int m1 = top_rows;
    drag_jacobian.resize(m1, nv);
    drag_velocity.resize(m1);
    drag_scaled.resize(m1, nv);
    drag_gram.resize(m1, m1);
    drag_factor_inverse.resize(m1, m1);
    drag_multipliers.resize(m1);
    range_drag_column.resize(m1);
    range_drag_component.resize(m1);
  }
  if (static_cast<int>(drag_damped.size()) <= top_rows) {
    drag_damped.resize(top_rows + 1);
  }
  if (top_rows > 0 && !drag_damped[top_rows]) {
    drag_damped[top_rows].emplace(top_rows);
  }
  // level 3's constraint rows: the drag's and at most every range row
  const Eigen::Index constraints = drag_jacobian.rows() + range_velocity.size();
  if (constraint_half.cols() < constraints) {
    constraint_half.resize(nv, constraints);
    constraint_schur.resize(constraints, constraints);
    constraint_multipliers.resize(constraints);
  }
  if (pin_jacobian.rows() < lower_rows) {
    const int m2 = lower_rows;
    pin_jacobian.resize(m2, nv);
    pin_velocity.resize(m2);
    pin_row_scale.resize(m2);
    pin_row_support.resize(m2);
    pin_scaled.resize(m2, nv);
    pin_residual.resize(m2);
  }
}

}  // namespace ik
