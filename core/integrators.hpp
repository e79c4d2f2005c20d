// Time integration of (q, v) on the configuration manifold.
#pragma once

#include <Eigen/Core>

#include "core/configuration.hpp"
#include "core/model.hpp"

namespace core {

/// q̇ in configuration coordinates (nq): 1-DOF q̇ = v; spherical q̇ = ½ q ⊗ (0, ω) with ω in the
/// child frame; free position ṗ = R v_linear, free quaternion as spherical.
void configuration_rate(const Model& model,
                        const Eigen::VectorXd& q,
                        const Eigen::VectorXd& v,
                        Eigen::VectorXd& qdot);

struct Rk4Workspace {
  Eigen::VectorXd q_stage, v_stage, kq[4], kv[4];
};

/// One classical fourth-order Runge–Kutta step of q̇ = rate(q, v), v̇ = accel(q, v), taken in the
/// quaternion-embedding coordinates and renormalized afterwards (fourth order overall).
/// accel(q, v, a_out) writes the acceleration (nv).
template <typename Accel>
void rk4_step(const Model& model,
              Eigen::VectorXd& q,
              Eigen::VectorXd& v,
              double dt,
              Accel&& accel,
              Rk4Workspace& w) {
  static constexpr double kStage[4] = {0.0, 0.5, 0.5, 1.0};
  for (int s = 0; s < 4; ++s) {
    w.kq[s].resize(model.nq);
    w.kv[s].resize(model.nv);
    if (s == 0) {
      w.q_stage = q;
      w.v_stage = v;
    } else {
      w.q_stage = q + (kStage[s] * dt) * w.kq[s - 1];
      w.v_stage = v + (kStage[s] * dt) * w.kv[s - 1];
    }
    configuration_rate(model, w.q_stage, w.v_stage, w.kq[s]);
    accel(w.q_stage, w.v_stage, w.kv[s]);
  }
  q += (dt / 6.0) * (w.kq[0] + 2.0 * w.kq[1] + 2.0 * w.kq[2] + w.kq[3]);
  v += (dt / 6.0) * (w.kv[0] + 2.0 * w.kv[1] + 2.0 * w.kv[2] + w.kv[3]);
  normalize(model, q);
}

}  // namespace core
