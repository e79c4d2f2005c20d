#include "core/newton_euler.hpp"

#include <Eigen/Cholesky>
#include <cassert>
#include <cmath>

namespace core {

namespace {

const Vector3 kZ = Vector3::UnitZ();

Matrix3 rot_x(double angle) {
  return Eigen::AngleAxisd(angle, Vector3::UnitX()).toRotationMatrix();
}
Matrix3 rot_z(double angle) {
  return Eigen::AngleAxisd(angle, Vector3::UnitZ()).toRotationMatrix();
}

// Everything the moment sums need, in base-frame coordinates. The paper writes each sum in
// frame j (ʲP_Ci, ʲR_i); a projection on z_j is the same number in any frame, so one common
// frame serves every joint.
struct ChainState {
  std::vector<Vector3> z;   // joint axes z_j                             (n)
  std::vector<Vector3> o;   // frame origins o_j                          (n)
  std::vector<Vector3> pc;  // link centres of mass p_Ci                  (n)
  std::vector<Matrix3> I;   // inertias about the COM, R_i I_i R_iᵀ       (n)
  std::vector<Matrix3> R;   // link orientations R_i = ⁰R_i               (n)
};

ChainState chain_state(const DhChain& chain, const Eigen::VectorXd& theta) {
  const int n = chain.size();
  assert(theta.size() == n);
  ChainState s;
  s.z.resize(n);
  s.o.resize(n);
  s.pc.resize(n);
  s.I.resize(n);
  s.R.resize(n);
  Transform X;  // ⁰T_j, built up joint by joint
  for (int j = 0; j < n; ++j) {
    const DhJoint& J = chain.joints[j];
    X = X * dh_transform(J, theta[j]);
    s.R[j] = X.R;
    s.z[j] = X.R * kZ;
    s.o[j] = X.p;
    s.pc[j] = X * J.com;
    s.I[j] = X.R * J.inertia * X.R.transpose();
  }
  return s;
}

}  // namespace

Transform dh_transform(const DhJoint& joint, double theta) {
  // Rot_x(α) Trans_x(a) Rot_z(θ) Trans_z(d): origin Rot_x(α)(a, 0, d) seen from frame j−1
  const Matrix3 Rx = rot_x(joint.alpha);
  const Matrix3 R = Rx * rot_z(theta + joint.theta_offset);
  const Vector3 p = Vector3(joint.a, 0, 0) + Rx * Vector3(0, 0, joint.d);
  return {R, p};
}

std::vector<Transform> dh_forward_kinematics(const DhChain& chain, const Eigen::VectorXd& theta) {
  std::vector<Transform> out(chain.size());
  Transform X;
  for (int j = 0; j < chain.size(); ++j) {
    X = X * dh_transform(chain.joints[j], theta[j]);
    out[j] = X;
  }
  return out;
}

Eigen::MatrixXd dh_mass_matrix(const DhChain& chain, const Eigen::VectorXd& theta) {
  const int n = chain.size();
  const ChainState s = chain_state(chain, theta);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
  // NE eqs. 7–8: the θ̈_k part of link i's inertial force is m_i (z_k × (p_Ci − o_k)) θ̈_k and of
  // its inertial moment I_i z_k θ̈_k (k ≤ i). Its moment about o_j, projected on z_j, is the
  // coefficient M_jk; by the scalar triple product z_j·(r × w) = (z_j × r)·w.
  for (int j = 0; j < n; ++j) {
    for (int k = 0; k <= j; ++k) {
      double m_jk = 0;
      for (int i = j; i < n; ++i) {  // links outboard of both joints: i ≥ max(j, k) = j
        const DhJoint& L = chain.joints[i];
        const Vector3 a_j = s.z[j].cross(s.pc[i] - s.o[j]);
        const Vector3 a_k = s.z[k].cross(s.pc[i] - s.o[k]);
        m_jk += L.mass * a_j.dot(a_k) + s.z[j].dot(s.I[i] * s.z[k]);
      }
      M(j, k) = M(k, j) = m_jk;
    }
  }
  return M;
}

Eigen::VectorXd dh_velocity_terms(const DhChain& chain,
                                  const Eigen::VectorXd& theta,
                                  const Eigen::VectorXd& theta_dot,
                                  const DhEndLoad* load) {
  const int n = chain.size();
  assert(theta_dot.size() == n);
  // NE eq. 6 and 8 with θ̈ = 0, in each link's own frame j (base at rest):
  //   ω_j   = ʲR_{j−1} ω_{j−1} + θ̇_j z
  //   C_ωj  = ʲR_{j−1} C_ω,j−1 + (ʲR_{j−1} ω_{j−1}) × θ̇_j z
  //   C_vj  = ʲR_{j−1} [C_ω,j−1 × ʲ⁻¹P_j + ω_{j−1} × (ω_{j−1} × ʲ⁻¹P_j) + C_v,j−1]
  //   C_vCj = C_ωj × P_Cj + ω_j × (ω_j × P_Cj) + C_vj
  std::vector<Vector3> w(n), Cw(n), CvC(n);
  std::vector<Matrix3> R0(n);  // ⁰R_j
  std::vector<Vector3> o(n), pc(n), z(n);
  Vector3 w_prev = Vector3::Zero(), Cw_prev = Vector3::Zero(), Cv_prev = Vector3::Zero();
  Transform X;
  for (int j = 0; j < n; ++j) {
    const DhJoint& J = chain.joints[j];
    const Transform T = dh_transform(J, theta[j]);  // ʲ⁻¹T_j: R = ʲ⁻¹R_j, p = ʲ⁻¹P_j
    const Matrix3 Rt = T.R.transpose();             // ʲR_{j−1}
    const Vector3 w_in = Rt * w_prev;
    w[j] = w_in + theta_dot[j] * kZ;
    Cw[j] = Rt * Cw_prev + w_in.cross(theta_dot[j] * kZ);
    const Vector3 Cv = Rt * (Cw_prev.cross(T.p) + w_prev.cross(w_prev.cross(T.p)) + Cv_prev);
    CvC[j] = Cw[j].cross(J.com) + w[j].cross(w[j].cross(J.com)) + Cv;
    w_prev = w[j];
    Cw_prev = Cw[j];
    Cv_prev = Cv;
    X = X * T;
    R0[j] = X.R;
    o[j] = X.p;
    pc[j] = X * J.com;
    z[j] = X.R * kZ;
  }
  // D'Alembert (NE eqs. 3, 5, 9): H_j = z_j · Σ_{i≥j} [(p_Ci − o_j) × m_i C_vCi + R_i N_i(θ̈=0)]
  // with N_i(θ̈=0) = I_i C_ωi + ω_i × I_i ω_i, accumulated from the tip inwards
  Eigen::VectorXd H(n);
  for (int j = 0; j < n; ++j) {
    Vector3 moment = Vector3::Zero();
    for (int i = j; i < n; ++i) {
      const DhJoint& L = chain.joints[i];
      const Vector3 F = L.mass * (R0[i] * CvC[i]);
      const Vector3 N = R0[i] * (L.inertia * Cw[i] + w[i].cross(L.inertia * w[i]));
      moment += (pc[i] - o[j]).cross(F) + N;
    }
    if (load) {
      // the load acts on the arm; its moment about o_j opposes the actuator (NE eq. 5: −z·N_Q)
      const Vector3 p_Q = R0[n - 1] * load->point_n + o[n - 1];
      moment -= (p_Q - o[j]).cross(load->force_0) + load->moment_0;
    }
    H[j] = z[j].dot(moment);
  }
  return H;
}

Eigen::VectorXd dh_gravity_terms(const DhChain& chain, const Eigen::VectorXd& theta) {
  const int n = chain.size();
  const ChainState s = chain_state(chain, theta);
  Eigen::VectorXd G(n);
  for (int j = 0; j < n; ++j) {
    Vector3 moment = Vector3::Zero();
    for (int i = j; i < n; ++i) {
      moment += (s.pc[i] - s.o[j]).cross(chain.joints[i].mass * chain.gravity);
    }
    G[j] = s.z[j].dot(moment);
  }
  return G;
}

Eigen::VectorXd dh_inverse_dynamics(const DhChain& chain,
                                    const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& theta_dot,
                                    const Eigen::VectorXd& theta_ddot,
                                    const DhEndLoad* load) {
  return dh_mass_matrix(chain, theta) * theta_ddot +
         dh_velocity_terms(chain, theta, theta_dot, load) - dh_gravity_terms(chain, theta);
}

Eigen::VectorXd dh_forward_dynamics(const DhChain& chain,
                                    const Eigen::VectorXd& theta,
                                    const Eigen::VectorXd& theta_dot,
                                    const Eigen::VectorXd& tau,
                                    const DhEndLoad* load) {
  const Eigen::MatrixXd M = dh_mass_matrix(chain, theta);
  const Eigen::VectorXd rhs =
      tau - dh_velocity_terms(chain, theta, theta_dot, load) + dh_gravity_terms(chain, theta);
  return M.llt().solve(rhs);
}

Eigen::VectorXd valve_closure_torques(const Eigen::VectorXd& stiffness,
                                      const Eigen::VectorXd& damping,
                                      const Eigen::VectorXd& theta_free,
                                      const Eigen::VectorXd& theta,
                                      const Eigen::VectorXd& theta_dot) {
  return -(stiffness.array() * (theta - theta_free).array()).matrix() -
         (damping.array() * theta_dot.array()).matrix();
}

}  // namespace core
