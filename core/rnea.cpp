#include "core/rnea.hpp"

#include "core/hinge.hpp"
#include "core/kinematics.hpp"
#include "core/motion_subspace.hpp"

namespace core {

namespace {

// f = I a + v ×* I v (RBDA Table 5.1), zero for a massless body
template <bool kWithVelocity>
inline Force body_force(const SpatialInertia& I, const Motion& v, const Motion& a) {
  if (is_massless(I)) return Force::Zero();
  Force f = inertia_times(I, a);
  if constexpr (kWithVelocity) f += cross(v, inertia_times(I, v));
  return f;
}

// Shared body of rnea: velocity terms only when `with_velocity`, accelerations only when given.
template <bool kWithVelocity, bool kWithAcceleration>
void rnea_passes(const Model& model,
                 Data& data,
                 const Eigen::VectorXd& q,
                 const Eigen::VectorXd& v,
                 const Eigen::VectorXd& a,
                 const std::vector<Force>* f_ext) {
  // forward pass: gravity enters as a fictitious upward acceleration of the world (RBDA §5.3)
  data.v[0] = Motion::Zero();
  data.a[0] = {Vector3::Zero(), -model.gravity};
  for (int i = 1; i < model.njoints; ++i) {
    const int p = model.parent[i];
    if (is_hinge(model, i)) {
      // S = [e_k; 0]: the joint terms are single entries
      with_axis(model.axis_index[i], [&](auto axis) {
        constexpr int k = axis();
        const HingeTransform<k> X{hinge_rotation<k>(model, i, q), model.X_PJ[i].p};
        data.X_P[i] = X.transform();
        data.a[i] = X.act_inverse(data.a[p]);
        if constexpr (kWithVelocity) {
          const double qd = v[model.idx_v[i]];
          data.v[i] = X.act_inverse(data.v[p]);
          data.v[i].angular[k] += qd;
          data.a[i] += cross_axis<k>(data.v[i], qd);
        } else {
          data.v[i] = Motion::Zero();
        }
        if constexpr (kWithAcceleration) data.a[i].angular[k] += a[model.idx_v[i]];
      });
    } else {
      data.X_P[i] = joint_transform(model, i, q);
      data.a[i] = data.X_P[i].act_inverse(data.a[p]);
      if constexpr (kWithVelocity) {
        const Motion vJ = joint_motion(model, i, v);
        data.v[i] = data.X_P[i].act_inverse(data.v[p]) + vJ;
        data.a[i] += data.v[i].cross(vJ);
      } else {
        data.v[i] = Motion::Zero();
      }
      if constexpr (kWithAcceleration) data.a[i] += joint_motion(model, i, a);
    }
    // f_i = I_i a_i + v_i ×* I_i v_i − f_ext,i
    data.f[i] = body_force<kWithVelocity>(model.inertia[i], data.v[i], data.a[i]);
    if (f_ext) data.f[i] -= (*f_ext)[i];
  }
  // backward pass: τ_i = S_iᵀ f_i, and the parent carries the child's force
  for (int i = model.njoints - 1; i > 0; --i) {
    const int p = model.parent[i];
    if (is_hinge(model, i)) {
      with_axis(model.axis_index[i], [&](auto axis) {
        constexpr int k = axis();
        data.tau[model.idx_v[i]] = data.f[i].angular[k];
        if (p > 0) data.f[p] += HingeTransform<k>::of(data.X_P[i]).act(data.f[i]);
      });
    } else {
      subspace_transpose(model, i, data.f[i],
                         data.tau.segment(model.idx_v[i], joint_nv(model.joint_type[i])));
      if (p > 0) data.f[p] += data.X_P[i].act(data.f[i]);
    }
  }
}

}  // namespace

const Eigen::VectorXd& rnea(const Model& model,
                            Data& data,
                            const Eigen::VectorXd& q,
                            const Eigen::VectorXd& v,
                            const Eigen::VectorXd& a) {
  rnea_passes<true, true>(model, data, q, v, a, nullptr);
  return data.tau;
}

const Eigen::VectorXd& rnea(const Model& model,
                            Data& data,
                            const Eigen::VectorXd& q,
                            const Eigen::VectorXd& v,
                            const Eigen::VectorXd& a,
                            const std::vector<Force>& f_ext) {
  rnea_passes<true, true>(model, data, q, v, a, &f_ext);
  return data.tau;
}

const Eigen::VectorXd& bias_forces(const Model& model,
                                   Data& data,
                                   const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& v) {
  rnea_passes<true, false>(model, data, q, v, v, nullptr);
  return data.tau;
}

const Eigen::VectorXd& gravity_forces(const Model& model, Data& data, const Eigen::VectorXd& q) {
  rnea_passes<false, false>(model, data, q, q, q, nullptr);
  return data.tau;
}

Force link_force_from_world(
    const Data& data, int link, const Vector3& f_W, const Vector3& p_W, const Vector3& moment_W) {
  // world wrench about the world origin, then into the link frame
  const Force f_world{moment_W + p_W.cross(f_W), f_W};
  return data.X_W[link].act_inverse(f_world);
}

}  // namespace core
