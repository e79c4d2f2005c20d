// Jacobians: joint motion axes in world, and world-aligned Jacobians of points on links.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/data.hpp"
#include "core/model.hpp"

namespace core {

/// Jacobian of a point fixed on a link, world-aligned: ω_W = angular * v, ṗ_W = linear * v.
struct FrameJacobian {
  Matrix3X angular;  // (3 x nv)
  Matrix3X linear;   // (3 x nv)
  FrameJacobian() = default;
  explicit FrameJacobian(int nv) : angular(Matrix3X::Zero(3, nv)), linear(Matrix3X::Zero(3, nv)) {}
};

/// Angular and linear parts of a point's velocity or acceleration, world-aligned.
struct PointMotion {
  Vector3 angular = Vector3::Zero();
  Vector3 linear = Vector3::Zero();
};

/// Forward kinematics plus every joint's motion axes in world: column k of data.J is the spatial
/// velocity (world axes, referenced at the world origin) produced by a unit v_k. Every link's
/// Jacobian is read off these columns (its ancestors' columns, shifted to the point).
/// @return data.J (6 x nv)
const Matrix6X& compute_joint_jacobians(const Model& model, Data& data, const Eigen::VectorXd& q);

/// The same from poses already in data.
/// Requires: forward_kinematics(model, data, q).
const Matrix6X& compute_joint_jacobians(const Model& model, Data& data);

/// The same from the world poses X_W (njoints) into J (6 x nv, sized).
void compute_joint_jacobians(const Model& model, const std::vector<Transform>& X_W, Matrix6X& J);

/// Writes the root-path columns of the world point p_W's Jacobian into rows of a stacked matrix:
/// its 3 angular rows from angular_row, its 3 linear rows from linear_row (-1: not wanted). The
/// rows' other columns are left as they are: the caller zeroes them.
/// Requires: compute_joint_jacobians(model, data, q).
void write_point_jacobian_rows(const Model& model,
                               const Data& data,
                               int link,
                               const Vector3& p_W,
                               int angular_row,
                               int linear_row,
                               Eigen::Ref<Eigen::MatrixXd> J);

/// World-aligned Jacobian of the point p_LinkPoint (link frame) on `link`. Allocation-free when
/// J_out is already sized (3 x nv).
/// Requires: compute_joint_jacobians(model, data, q).
void point_jacobian(const Model& model,
                    const Data& data,
                    int link,
                    const Vector3& p_LinkPoint,
                    FrameJacobian& J_out);

/// Dense world-aligned Jacobians of a fixed set of points on links, updated together. A link's
/// Jacobian is nonzero only in the columns of the joints on its root path. Those are the only
/// columns an update writes: the others are zeroed once, at construction, and never touched
/// again, so an update costs the points' depths rather than nv per point.
class LinkJacobians {
 public:
  struct Point {
    int link = 0;
    Vector3 p_LinkPoint = Vector3::Zero();
  };

  /// @throws std::invalid_argument naming the point whose link is not a link of the model
  LinkJacobians(const Model& model, std::vector<Point> points);

  /// Recomputes every point's Jacobian. Allocation-free.
  /// Requires: compute_joint_jacobians(model, data, q), on the model given at construction.
  void update(const Model& model, const Data& data);

  int size() const { return static_cast<int>(points_.size()); }
  const Point& point(int k) const { return points_[k]; }
  const FrameJacobian& operator[](int k) const { return jacobians_[k]; }

 private:
  std::vector<Point> points_;
  std::vector<int> path_last_v_;  // per point: the last coordinate on its link's root path
  std::vector<FrameJacobian> jacobians_;
};

/// Velocity of a point on a link. Requires: forward_kinematics(model, data, q, v).
PointMotion point_velocity(const Model& model,
                           const Data& data,
                           int link,
                           const Vector3& p_LinkPoint);

/// J̇·v of a point on a link: its classical acceleration when the joint accelerations are zero.
/// Requires: forward_kinematics(model, data, q, v).
PointMotion point_jdot_v(const Model& model,
                         const Data& data,
                         int link,
                         const Vector3& p_LinkPoint);

/// Classical acceleration of a point on a link. Requires: forward_kinematics(model, data, q, v, a).
PointMotion point_acceleration(const Model& model,
                               const Data& data,
                               int link,
                               const Vector3& p_LinkPoint);

}  // namespace core
