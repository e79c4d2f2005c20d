#include "core/jacobian.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <string>

#include "core/kinematics.hpp"

namespace core {

const Matrix6X& compute_joint_jacobians(const Model& model, Data& data, const Eigen::VectorXd& q) {
  forward_kinematics(model, data, q);
  return compute_joint_jacobians(model, data);
}

const Matrix6X& compute_joint_jacobians(const Model& model, Data& data) {
  compute_joint_jacobians(model, data.X_W, data.J);
  return data.J;
}

void compute_joint_jacobians(const Model& model, const std::vector<Transform>& X_W, Matrix6X& J) {
  for (int i = 1; i < model.njoints; ++i) {
    const Matrix3& R = X_W[i].R;
    const Vector3& p = X_W[i].p;
    const int c = model.idx_v[i];
    // a rotation ω about an axis through p moves the world origin with p × ω
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute: {
        const int k = model.axis_index[i];
        const Vector3 w = k >= 0 ? Vector3(R.col(k)) : Vector3(R * model.axis[i]);
        const Vector3 v = p.cross(w);
        double* Jc = J.data() + 6 * c;  // columns are contiguous 6-vectors
        Jc[0] = w[0], Jc[1] = w[1], Jc[2] = w[2];
        Jc[3] = v[0], Jc[4] = v[1], Jc[5] = v[2];
        break;
      }
      case JointType::kPrismatic:
        J.col(c).head<3>().setZero();
        J.col(c).tail<3>() = R * model.axis[i];
        break;
      case JointType::kSpherical:
        for (int k = 0; k < 3; ++k) {
          J.col(c + k).head<3>() = R.col(k);
          J.col(c + k).tail<3>() = p.cross(R.col(k));
        }
        break;
      case JointType::kFree:
        for (int k = 0; k < 3; ++k) {
          J.col(c + k).head<3>() = R.col(k);
          J.col(c + k).tail<3>() = p.cross(R.col(k));
          J.col(c + 3 + k).head<3>().setZero();
          J.col(c + 3 + k).tail<3>() = R.col(k);
        }
        break;
    }
  }
}

namespace {
// Column c of the Jacobian of the world point p = (px, py, pz) from the joint's spatial axis
// a = (ω, v_O) at the world origin: ω, and the point's velocity v_O + ω × p.
inline void point_column(
    const double* a, double px, double py, double pz, double* __restrict w, double* __restrict v) {
  w[0] = a[0], w[1] = a[1], w[2] = a[2];
  v[0] = a[3] + (a[1] * pz - a[2] * py);
  v[1] = a[4] + (a[2] * px - a[0] * pz);
  v[2] = a[5] + (a[0] * py - a[1] * px);
}

// Columns first..last of a point's Jacobian into the 3-row angular and linear blocks. The
// outputs are declared apart from the axes and from each other (restrict), so the loop runs two
// columns at a time without run-time overlap checks. Kept out of line: inlined into its caller,
// GCC drops what restrict tells it and versions the loop again (4 % more instructions).
[[gnu::noinline]] void write_columns(const double* __restrict axes,
                                     int first,
                                     int last,
                                     const Vector3& p_W,
                                     double* __restrict angular,
                                     double* __restrict linear) {
  const double px = p_W[0], py = p_W[1], pz = p_W[2];
  for (int c = first; c <= last; ++c)
    point_column(axes + 6 * c, px, py, pz, angular + 3 * c, linear + 3 * c);
}

// writes the columns on the root path ending at coordinate last (Model::path_last_v of the
// link) of the Jacobian of the world point p_W fixed on the link, leaving the others as they are
void write_root_path_columns(
    const Model& model, const Data& data, int last, const Vector3& p_W, FrameJacobian& J_out) {
  double* const angular = J_out.angular.data();
  double* const linear = J_out.linear.data();
  for_each_ancestor_run(model, last, [&](int start, int n) {
    write_columns(data.J.data(), start, start + n - 1, p_W, angular, linear);
  });
}
}  // namespace

void point_jacobian(const Model& model,
                    const Data& data,
                    int link,
                    const Vector3& p_LinkPoint,
                    FrameJacobian& J_out) {
  J_out.angular.setZero(3, model.nv);
  J_out.linear.setZero(3, model.nv);
  write_root_path_columns(model, data, model.path_last_v(link), data.X_W[link] * p_LinkPoint,
                          J_out);
}

void write_point_jacobian_rows(const Model& model,
                               const Data& data,
                               int link,
                               const Vector3& p_W,
                               int angular_row,
                               int linear_row,
                               Eigen::Ref<Eigen::MatrixXd> J) {
  double* const base = J.data();
  const Eigen::Index stride = J.outerStride();
  const double px = p_W[0], py = p_W[1], pz = p_W[2];
  for_each_ancestor_run(model, model.path_last_v(link), [&](int start, int n) {
    for (int c = start; c < start + n; ++c) {
      double w[3], v[3];
      point_column(data.J.data() + 6 * c, px, py, pz, w, v);
      double* const column = base + c * stride;
      if (angular_row >= 0) std::copy(w, w + 3, column + angular_row);
      if (linear_row >= 0) std::copy(v, v + 3, column + linear_row);
    }
  });
}

LinkJacobians::LinkJacobians(const Model& model, std::vector<Point> points)
    : points_(std::move(points)) {
  for (std::size_t k = 0; k < points_.size(); ++k) {
    if (points_[k].link < 1 || points_[k].link >= model.njoints) {
      throw std::invalid_argument("LinkJacobians: point " + std::to_string(k) + " is on link " +
                                  std::to_string(points_[k].link) +
                                  ", but the model's links are 1 to " +
                                  std::to_string(model.njoints - 1));
    }
  }
  jacobians_.assign(points_.size(), FrameJacobian(model.nv));
  for (const Point& point : points_) path_last_v_.push_back(model.path_last_v(point.link));
}

void LinkJacobians::update(const Model& model, const Data& data) {
  assert(jacobians_.empty() || jacobians_[0].linear.cols() == model.nv);
  for (std::size_t k = 0; k < points_.size(); ++k) {
    const Point& point = points_[k];
    write_root_path_columns(model, data, path_last_v_[k], data.X_W[point.link] * point.p_LinkPoint,
                            jacobians_[k]);
  }
}

PointMotion point_velocity(const Model& /*model*/,
                           const Data& data,
                           int link,
                           const Vector3& p_LinkPoint) {
  const Motion& v = data.v[link];
  const Matrix3& R = data.X_W[link].R;
  return {R * v.angular, R * (v.linear + v.angular.cross(p_LinkPoint))};
}

namespace {
// classical acceleration of a body point from a spatial acceleration (link frame)
PointMotion classical_acceleration(const Data& data, int link, const Motion& a, const Vector3& r) {
  const Motion& v = data.v[link];
  const Matrix3& R = data.X_W[link].R;
  const Vector3 v_point = v.linear + v.angular.cross(r);
  return {R * a.angular, R * (a.linear + a.angular.cross(r) + v.angular.cross(v_point))};
}
}  // namespace

PointMotion point_jdot_v(const Model& /*model*/,
                         const Data& data,
                         int link,
                         const Vector3& p_LinkPoint) {
  return classical_acceleration(data, link, data.a_bias[link], p_LinkPoint);
}

PointMotion point_acceleration(const Model& /*model*/,
                               const Data& data,
                               int link,
                               const Vector3& p_LinkPoint) {
  return classical_acceleration(data, link, data.a[link], p_LinkPoint);
}

}  // namespace core
