// Tests for core/newton_euler.hpp (the [NE] paper's D'Alembert path, digest §2.14) against our
// RNEA, CRBA and ABA on manipulator5, the paper's inverse-dynamics example (cubic joint
// trajectories through three points with the 3200 N load, characters/README.md), and tests for
// core/model_edit.hpp.
//
// With PINDRAG_WRITE_FIGURES=<folder> set, NewtonEuler.PaperInverseDynamicsExample also writes
// <folder>/manipulator5-torques.svg, the five joint torques over the trajectory (docs/dynamics.md).
#include "core/newton_euler.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <random>
#include <sstream>

#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "core/model_edit.hpp"
#include "core/rnea.hpp"
#include "io/bundled_characters.hpp"
#include "io/urdf.hpp"

namespace {

using core::DhChain;
using core::DhJoint;
using core::Matrix3;
using core::Vector3;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr double kG = 9.81;
constexpr double kLoadWeight = 3200.0;  // N, [NE] §3

// inertia of a solid box with full extents (x, y, z) and of a solid cylinder along z, about the COM
Matrix3 box_inertia(double m, double x, double y, double z) {
  return Vector3(m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12)
      .asDiagonal();
}
Matrix3 cylinder_inertia(double m, double r, double h) {
  const double t = m * (3 * r * r + h * h) / 12;
  return Vector3(t, t, m * r * r / 2).asDiagonal();
}

// A rigid mass added to a DH link: masses add, the COM is the weighted mean, inertias move to the
// common COM by the parallel-axis theorem.
void lump(DhJoint& link, double m, const Vector3& c, const Matrix3& I_c) {
  const double M = link.mass + m;
  const Vector3 com = (link.mass * link.com + m * c) / M;
  auto shift = [](double mass, const Vector3& r) {
    return mass * (r.squaredNorm() * Matrix3::Identity() - r * r.transpose());
  };
  link.inertia = link.inertia + shift(link.mass, link.com - com) + I_c + shift(m, c - com);
  link.mass = M;
  link.com = com;
}

// manipulator5 from the DH and mass tables of characters/README.md (modified DH); the inertias
// come from the shapes the table names, the load's from its printed values (as in the URDF).
// With `with_load` false the load is left off (it can then be applied as an external force).
DhChain manipulator5_dh(bool with_load = true) {
  DhChain c;
  c.gravity = Vector3(0, 0, -kG);
  auto joint = [](double alpha, double a, double d, double m, const Vector3& com,
                  const Matrix3& I) {
    DhJoint j;
    j.alpha = alpha;
    j.a = a;
    j.d = d;
    j.mass = m;
    j.com = com;
    j.inertia = I;
    return j;
  };
  c.joints.push_back(joint(0, 0, 0.9, 250, {0.08, 0, -0.35}, cylinder_inertia(250, 0.25, 0.7)));
  c.joints.push_back(
      joint(kPi / 2, 0.3, 0, 180, {0.85, 0.04, 0}, box_inertia(180, 1.8, 0.30, 0.25)));
  c.joints.push_back(joint(0, 1.8, 0, 120, {0.70, 0.03, 0}, box_inertia(120, 1.5, 0.25, 0.20)));
  c.joints.push_back(joint(0, 1.5, 0, 40, {0.20, 0, 0}, box_inertia(40, 0.4, 0.2, 0.2)));
  c.joints.push_back(joint(kPi / 2, 0.4, 0, 60, {0, 0, 0.15}, cylinder_inertia(60, 0.15, 0.30)));
  if (with_load) {
    lump(c.joints[4], 326.1978, {0, 0, 0.475}, Vector3::Constant(6.659871).asDiagonal());
  }
  return c;
}

std::shared_ptr<const core::Model> manipulator5() {
  return io::load_character("manipulator5").model;
}

// our velocity index of DH joint j (joints are named joint1 … joint5)
std::vector<int> dh_to_ours(const core::Model& m) {
  std::vector<int> idx;
  for (int j = 1; j <= 5; ++j) {
    const int i = m.joint_index("joint" + std::to_string(j));
    EXPECT_GT(i, 0);
    idx.push_back(m.idx_v[i]);
  }
  return idx;
}

std::string sci(double x) {
  std::ostringstream o;
  o << std::scientific << std::setprecision(2) << x;
  return o.str();
}

double rel(const Eigen::MatrixXd& x, const Eigen::MatrixXd& ref) {
  return (x - ref).cwiseAbs().maxCoeff() / ref.cwiseAbs().maxCoeff();
}

struct DhState {
  Eigen::VectorXd theta, theta_dot, theta_ddot, tau;
};

DhState random_dh_state(const core::Model& m, std::uint64_t seed) {
  // joint angles inside the URDF limits (random_configuration), rates and torques of the size a
  // moving arm sees
  const Eigen::VectorXd q = core::random_configuration(m, seed);
  const std::vector<int> idx = dh_to_ours(m);
  DhState s;
  s.theta.resize(5);
  for (int j = 0; j < 5; ++j) s.theta[j] = q[idx[j]];
  std::mt19937_64 gen(seed);
  auto uniform = [&] { return 2.0 * static_cast<double>(gen() >> 11) * 0x1.0p-53 - 1.0; };
  s.theta_dot = Eigen::VectorXd::NullaryExpr(5, [&](Eigen::Index) { return 0.8 * uniform(); });
  s.theta_ddot = Eigen::VectorXd::NullaryExpr(5, [&](Eigen::Index) { return 2.0 * uniform(); });
  s.tau = Eigen::VectorXd::NullaryExpr(5, [&](Eigen::Index) { return 5000.0 * uniform(); });
  return s;
}

// our q, v (a) from DH values; manipulator5 has only the five revolute joints
Eigen::VectorXd to_ours(const core::Model& m, const Eigen::VectorXd& x) {
  const std::vector<int> idx = dh_to_ours(m);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(m.nv);
  for (int j = 0; j < 5; ++j) out[idx[j]] = x[j];
  return out;
}
Eigen::VectorXd from_ours(const core::Model& m, const Eigen::VectorXd& x) {
  const std::vector<int> idx = dh_to_ours(m);
  Eigen::VectorXd out(5);
  for (int j = 0; j < 5; ++j) out[j] = x[idx[j]];
  return out;
}
Eigen::MatrixXd from_ours(const core::Model& m, const Eigen::MatrixXd& M) {
  const std::vector<int> idx = dh_to_ours(m);
  Eigen::MatrixXd out(5, 5);
  for (int j = 0; j < 5; ++j) {
    for (int k = 0; k < 5; ++k) out(j, k) = M(idx[j], idx[k]);
  }
  return out;
}

TEST(NewtonEuler, DhFramesAreTheUrdfLinkFrames) {
  // the README's DH table and the URDF describe the same arm: every link frame and centre of mass
  // agrees after the Z-up → Y-up change of basis (X_ours = (C R Cᵀ, C p))
  const auto m = manipulator5();
  ASSERT_EQ(m->nv, 5);
  const DhChain dh = manipulator5_dh(false);
  const Matrix3 C = io::urdf_to_y_up();
  core::Data d(*m);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const DhState s = random_dh_state(*m, seed);
    core::forward_kinematics(*m, d, to_ours(*m, s.theta).eval());
    const std::vector<core::Transform> X = core::dh_forward_kinematics(dh, s.theta);
    for (int j = 0; j < 5; ++j) {
      const int link = m->link_index("link" + std::to_string(j + 1));
      EXPECT_LT((d.X_W[link].R - C * X[j].R * C.transpose()).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LT((d.X_W[link].p - C * X[j].p).cwiseAbs().maxCoeff(), 1e-14);
      EXPECT_LT((d.X_W[link] * m->inertia[link].com() - C * (X[j] * dh.joints[j].com)).norm(),
                1e-14);
    }
  }
}

TEST(NewtonEuler, MassMatrixEqualsCrba) {
  const auto m = manipulator5();
  const DhChain dh = manipulator5_dh();
  core::Data d(*m);
  double worst = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const DhState s = random_dh_state(*m, seed);
    const Eigen::MatrixXd M_ne = core::dh_mass_matrix(dh, s.theta);
    const Eigen::MatrixXd M_crba = from_ours(*m, core::crba(*m, d, to_ours(*m, s.theta)));
    EXPECT_EQ(M_ne, M_ne.transpose());
    worst = std::max(worst, rel(M_ne, M_crba));
  }
  EXPECT_LT(worst, 1e-10);
  RecordProperty("max_rel_mass_matrix", sci(worst));
}

TEST(NewtonEuler, InverseDynamicsEqualsRnea) {
  const auto m = manipulator5();
  const DhChain dh = manipulator5_dh();
  core::Data d(*m);
  double worst_tau = 0, worst_bias = 0, worst_g = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const DhState s = random_dh_state(*m, seed);
    const Eigen::VectorXd q = to_ours(*m, s.theta), v = to_ours(*m, s.theta_dot),
                          a = to_ours(*m, s.theta_ddot);
    const Eigen::VectorXd tau_ne =
        core::dh_inverse_dynamics(dh, s.theta, s.theta_dot, s.theta_ddot);
    worst_tau = std::max(worst_tau, rel(tau_ne, from_ours(*m, core::rnea(*m, d, q, v, a))));
    // b = H − G, and our generalized gravity (torque that holds the pose) is −G
    const Eigen::VectorXd H = core::dh_velocity_terms(dh, s.theta, s.theta_dot);
    const Eigen::VectorXd G = core::dh_gravity_terms(dh, s.theta);
    worst_bias = std::max(worst_bias, rel(H - G, from_ours(*m, core::bias_forces(*m, d, q, v))));
    worst_g = std::max(worst_g, rel(-G, from_ours(*m, core::gravity_forces(*m, d, q))));
  }
  EXPECT_LT(worst_tau, 1e-10);
  EXPECT_LT(worst_bias, 1e-10);
  EXPECT_LT(worst_g, 1e-10);
  RecordProperty("max_rel_tau", sci(worst_tau));
  RecordProperty("max_rel_bias", sci(worst_bias));
}

TEST(NewtonEuler, ForwardDynamicsEqualsAba) {
  const auto m = manipulator5();
  const DhChain dh = manipulator5_dh();
  core::Data d(*m);
  double worst = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const DhState s = random_dh_state(*m, seed);
    const Eigen::VectorXd a_ne = core::dh_forward_dynamics(dh, s.theta, s.theta_dot, s.tau);
    const Eigen::VectorXd a_aba = from_ours(
        *m, core::aba(*m, d, to_ours(*m, s.theta), to_ours(*m, s.theta_dot), to_ours(*m, s.tau)));
    worst = std::max(worst, rel(a_ne, a_aba));
    // and it inverts the inverse problem
    EXPECT_LT(rel(core::dh_inverse_dynamics(dh, s.theta, s.theta_dot, a_ne), s.tau), 1e-12);
  }
  EXPECT_LT(worst, 1e-10);
  RecordProperty("max_rel_accelerations", sci(worst));
}

TEST(NewtonEuler, LoadAsExternalForceEqualsLoadAsMassAtRest) {
  // at rest only weights act, so hanging 3200 N at the load centre as an external force (N_Q of
  // NE eq. 5) must need the same torques as carrying the load's mass
  const auto m = manipulator5();
  const DhChain with_mass = manipulator5_dh(true);
  const DhChain without = manipulator5_dh(false);
  core::DhEndLoad load;
  load.force_0 = Vector3(0, 0, -326.1978 * kG);
  load.point_n = Vector3(0, 0, 0.475);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(5);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const DhState s = random_dh_state(*m, seed);
    const Eigen::VectorXd a = core::dh_inverse_dynamics(with_mass, s.theta, zero, zero);
    const Eigen::VectorXd b = core::dh_inverse_dynamics(without, s.theta, zero, zero, &load);
    EXPECT_LT(rel(b, a), 1e-12);
    // the load alone: z_j · ((p_Q − o_j) × F) for the joint-2 boom, by hand
    const std::vector<core::Transform> X = core::dh_forward_kinematics(without, s.theta);
    const Vector3 p_Q = X[4] * load.point_n;
    const double tau2_load = -X[1].R.col(2).dot((p_Q - X[1].p).cross(load.force_0));
    const Eigen::VectorXd no_load = core::dh_inverse_dynamics(without, s.theta, zero, zero);
    EXPECT_NEAR(b[1] - no_load[1], tau2_load, 1e-9 * std::abs(tau2_load));
  }
}

TEST(NewtonEuler, ValveClosureDissipatesEnergy) {
  // NE eq. 14 after a sudden valve closure: joint springs and dampers. With damping the total
  // energy (kinetic + weight + springs) never rises; without it RK4 keeps it to integration error.
  const DhChain dh = manipulator5_dh();
  const Eigen::VectorXd k = Eigen::VectorXd::Constant(5, 2e5);
  const Eigen::VectorXd theta0 = (Eigen::VectorXd(5) << 0.3, 0.4, -0.8, 0.4, 0.3).finished();
  auto energy = [&](const Eigen::VectorXd& th, const Eigen::VectorXd& thd) {
    const std::vector<core::Transform> X = core::dh_forward_kinematics(dh, th);
    double V = 0;
    for (int j = 0; j < 5; ++j) V -= dh.joints[j].mass * dh.gravity.dot(X[j] * dh.joints[j].com);
    const double T = 0.5 * thd.dot(core::dh_mass_matrix(dh, th) * thd);
    return T + V + 0.5 * (k.array() * (th - theta0).array().square()).sum();
  };
  // RK4 from a moving state for 1 s; returns the largest energy rise in one step, the largest
  // drift from the start and the final energy
  struct Run {
    double rise = 0, drift = 0, E0 = 0, E_end = 0;
  };
  auto simulate = [&](double damping, double dt) {
    const Eigen::VectorXd dmp = Eigen::VectorXd::Constant(5, damping);
    Eigen::VectorXd th = theta0, thd = (Eigen::VectorXd(5) << 0.2, -0.3, 0.25, 0.1, 0.4).finished();
    auto accel = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& xd) {
      return core::dh_forward_dynamics(dh, x, xd,
                                       core::valve_closure_torques(k, dmp, theta0, x, xd));
    };
    Run r;
    r.E0 = energy(th, thd);
    double prev = r.E0;
    const int steps = static_cast<int>(std::lround(1.0 / dt));
    for (int step = 0; step < steps; ++step) {
      const Eigen::VectorXd k1v = accel(th, thd), k1x = thd;
      const Eigen::VectorXd k2v = accel(th + 0.5 * dt * k1x, thd + 0.5 * dt * k1v),
                            k2x = thd + 0.5 * dt * k1v;
      const Eigen::VectorXd k3v = accel(th + 0.5 * dt * k2x, thd + 0.5 * dt * k2v),
                            k3x = thd + 0.5 * dt * k2v;
      const Eigen::VectorXd k4v = accel(th + dt * k3x, thd + dt * k3v), k4x = thd + dt * k3v;
      th += dt / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      thd += dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      const double E = energy(th, thd);
      r.rise = std::max(r.rise, E - prev);
      r.drift = std::max(r.drift, std::abs(E - r.E0));
      prev = E;
    }
    r.E_end = prev;
    return r;
  };
  // undamped: energy is conserved up to RK4's error, which falls ~16x when the step halves
  const Run coarse = simulate(0, 1e-3), fine = simulate(0, 5e-4);
  EXPECT_LT(fine.drift / std::abs(fine.E0), 5e-9);
  EXPECT_GT(coarse.drift / fine.drift, 10.0) << coarse.drift << " vs " << fine.drift;
  // damped: energy never rises and the dampers take a good part of the kinetic energy out
  const Run damped = simulate(5e3, 1e-3);
  EXPECT_LT(damped.rise, 1e-9 * std::abs(damped.E0));
  EXPECT_LT(damped.E_end, damped.E0 - 1.0);
}

// ------------------------------------------------------------------------------------------------
// the paper's inverse-dynamics example (characters/README.md, "A test trajectory")

struct Sample {
  double t;
  Eigen::VectorXd theta, theta_dot, theta_ddot;
};

// per joint: two cubic segments through start, middle and end with zero end velocities and the
// middle velocity 3(θ_end − θ_start)/(4h) that makes θ̈ continuous (clamped spline, h = T/2)
Sample trajectory(double t) {
  constexpr double T = 10.0, h = T / 2;
  const double points[3][5] = {{0, 20, -40, 20, 0}, {45, 35, -75, 40, 45}, {90, 10, -30, 20, 90}};
  Sample s{t, Eigen::VectorXd(5), Eigen::VectorXd(5), Eigen::VectorXd(5)};
  const int seg = t < h ? 0 : 1;
  const double u = t - seg * h;
  for (int j = 0; j < 5; ++j) {
    const double th0 = points[0][j] * kDeg, th2 = points[2][j] * kDeg;
    const double v_mid = 3 * (th2 - th0) / (4 * h);
    const double a = points[seg][j] * kDeg, b = points[seg + 1][j] * kDeg;
    const double va = seg == 0 ? 0 : v_mid, vb = seg == 0 ? v_mid : 0;
    const double D = b - a;
    const double c2 = (3 * D - (2 * va + vb) * h) / (h * h);
    const double c3 = ((va + vb) * h - 2 * D) / (h * h * h);
    s.theta[j] = a + va * u + c2 * u * u + c3 * u * u * u;
    s.theta_dot[j] = va + 2 * c2 * u + 3 * c3 * u * u;
    s.theta_ddot[j] = 2 * c2 + 6 * c3 * u;
  }
  return s;
}

// the torques as an SVG line plot (kN·m against s), one polyline per joint; dashed, the part
// that only holds the weights (−G)
std::string torque_plot(const std::vector<double>& t,
                        const std::vector<Eigen::VectorXd>& tau,
                        const std::vector<Eigen::VectorXd>& hold) {
  constexpr double W = 760, H = 440, left = 70, right = 150, top = 40, bottom = 50;
  double lo = 0, hi = 0;
  for (const auto& x : tau) {
    lo = std::min(lo, x.minCoeff() / 1000);
    hi = std::max(hi, x.maxCoeff() / 1000);
  }
  const double step = 5.0;  // kN·m between grid lines
  lo = std::floor(lo / step) * step;
  hi = std::ceil(hi / step) * step;
  auto X = [&](double s) { return left + (W - left - right) * s / t.back(); };
  auto Y = [&](double kNm) { return top + (H - top - bottom) * (hi - kNm) / (hi - lo); };
  std::ostringstream o;
  o << std::fixed << std::setprecision(1);
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << W / 2 - 60 << "\" y=\"22\" font-size=\"14\" text-anchor=\"middle\">"
    << "manipulator5: joint torques along the three-point cubic trajectory (3200 N load)</text>\n";
  for (double g = lo; g <= hi + 1e-9; g += step) {
    o << "<line x1=\"" << left << "\" y1=\"" << Y(g) << "\" x2=\"" << W - right << "\" y2=\""
      << Y(g) << "\" stroke=\"" << (g == 0 ? "#888" : "#e4e4e4") << "\"/>\n"
      << "<text x=\"" << left - 6 << "\" y=\"" << Y(g) + 4 << "\" text-anchor=\"end\">" << g
      << "</text>\n";
  }
  for (int s = 0; s <= 10; ++s) {
    o << "<line x1=\"" << X(s) << "\" y1=\"" << H - bottom << "\" x2=\"" << X(s) << "\" y2=\""
      << H - bottom + 5 << "\" stroke=\"black\"/>\n"
      << "<text x=\"" << X(s) << "\" y=\"" << H - bottom + 18 << "\" text-anchor=\"middle\">" << s
      << "</text>\n";
  }
  o << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << W - left - right
    << "\" height=\"" << H - top - bottom << "\" fill=\"none\" stroke=\"black\"/>\n"
    << "<text x=\"" << (left + W - right) / 2 << "\" y=\"" << H - 12
    << "\" text-anchor=\"middle\">time (s)</text>\n"
    << "<text x=\"18\" y=\"" << (top + H - bottom) / 2 << "\" text-anchor=\"middle\" transform="
    << "\"rotate(-90 18 " << (top + H - bottom) / 2 << ")\">joint torque (kN·m)</text>\n";
  const char* colours[5] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd"};
  for (int j = 0; j < 5; ++j) {
    o << "<polyline fill=\"none\" stroke-width=\"2\" stroke=\"" << colours[j] << "\" points=\"";
    for (size_t k = 0; k < t.size(); ++k) o << X(t[k]) << "," << Y(tau[k][j] / 1000) << " ";
    o << "\"/>\n";
    o << "<polyline fill=\"none\" stroke-width=\"1\" stroke-dasharray=\"5,4\" stroke=\""
      << colours[j] << "\" points=\"";
    for (size_t k = 0; k < t.size(); ++k) o << X(t[k]) << "," << Y(hold[k][j] / 1000) << " ";
    o << "\"/>\n";
    const double ly = top + 20 + 22 * j;
    o << "<line x1=\"" << W - right + 15 << "\" y1=\"" << ly << "\" x2=\"" << W - right + 40
      << "\" y2=\"" << ly << "\" stroke-width=\"2\" stroke=\"" << colours[j] << "\"/>\n"
      << "<text x=\"" << W - right + 46 << "\" y=\"" << ly + 4 << "\">τ" << j + 1 << "</text>\n";
  }
  o << "<line x1=\"" << W - right + 15 << "\" y1=\"" << top + 140 << "\" x2=\"" << W - right + 40
    << "\" y2=\"" << top + 140 << "\" stroke=\"black\" stroke-dasharray=\"5,4\"/>\n"
    << "<text x=\"" << W - right + 46 << "\" y=\"" << top + 144 << "\">weights only</text>\n"
    << "<text x=\"" << W - right + 15 << "\" y=\"" << top + 162
    << "\" font-size=\"10\">(−G, no motion)</text>\n";
  o << "</svg>\n";
  return o.str();
}

TEST(NewtonEuler, PaperInverseDynamicsExample) {
  const auto m = manipulator5();
  const DhChain dh = manipulator5_dh();
  core::Data d(*m);
  // the trajectory passes the three points, starts and stops at rest, and keeps the load level
  // (θ2 + θ3 + θ4 = 0 at every point, and the spline is linear in its data)
  const Sample s0 = trajectory(0), s5 = trajectory(5), s10 = trajectory(10);
  EXPECT_NEAR(s5.theta[0], 45 * kDeg, 1e-15);
  EXPECT_NEAR(s10.theta[2], -30 * kDeg, 1e-15);
  EXPECT_EQ(s0.theta_dot.norm(), 0.0);
  EXPECT_LT(s10.theta_dot.norm(), 1e-15);
  EXPECT_LT((trajectory(5 - 1e-9).theta_ddot - trajectory(5).theta_ddot).norm(), 1e-8);

  std::vector<double> times;
  std::vector<Eigen::VectorXd> torques, holding;
  double worst = 0, level = 0;
  for (int k = 0; k <= 200; ++k) {
    const Sample s = trajectory(0.05 * k);
    level = std::max(level, std::abs(s.theta[1] + s.theta[2] + s.theta[3]));
    const Eigen::VectorXd tau = core::dh_inverse_dynamics(dh, s.theta, s.theta_dot, s.theta_ddot);
    const Eigen::VectorXd tau_rnea =
        from_ours(*m, core::rnea(*m, d, to_ours(*m, s.theta), to_ours(*m, s.theta_dot),
                                 to_ours(*m, s.theta_ddot)));
    worst = std::max(worst, rel(tau, tau_rnea));
    times.push_back(s.t);
    torques.push_back(tau);
    holding.push_back(-core::dh_gravity_terms(dh, s.theta));
  }
  EXPECT_LT(level, 1e-15);
  EXPECT_LT(worst, 1e-10);
  RecordProperty("max_rel_tau_along_trajectory", sci(worst));
  // at rest (start and end) the velocity terms vanish; the weights have no moment about the
  // vertical slewing axis, so joint 1 only ever accelerates the arm
  EXPECT_EQ(core::dh_velocity_terms(dh, s0.theta, s0.theta_dot).norm(), 0.0);
  for (const double t : {0.0, 2.5, 5.0, 7.5, 10.0}) {
    EXPECT_LT(std::abs(core::dh_gravity_terms(dh, trajectory(t).theta)[0]), 1e-9) << "t " << t;
  }
  // every torque stays inside the actuator efforts of the URDF
  for (int j = 0; j < 5; ++j) {
    const double effort = m->limits[m->joint_index("joint" + std::to_string(j + 1))].effort;
    double peak = 0;
    for (const auto& tau : torques) peak = std::max(peak, std::abs(tau[j]));
    EXPECT_LT(peak, effort) << "joint " << j + 1;
    RecordProperty("peak_tau" + std::to_string(j + 1), sci(peak));
  }
  // the load's weight is 3200 N (the paper's figure)
  EXPECT_NEAR(326.1978 * kG, kLoadWeight, 0.01);

  if (const char* dir = std::getenv("PINDRAG_WRITE_FIGURES"); dir && *dir) {
    const std::string path = std::string(dir) + "/manipulator5-torques.svg";
    std::ofstream(path) << torque_plot(times, torques, holding);
    std::cout << "wrote " << path << "\n";
  }
}

// ------------------------------------------------------------------------------------------------
// core/model_edit.hpp

TEST(ModelEdit, ToBuilderRebuildsTheSameModel) {
  for (const auto& m : {core::build_human_figure({}), manipulator5()}) {
    const auto copy = core::to_builder(*m).finalize();
    ASSERT_EQ(copy->njoints, m->njoints);
    EXPECT_EQ(copy->link_name, m->link_name);
    EXPECT_EQ(copy->joint_name, m->joint_name);
    EXPECT_EQ(copy->joint_type, m->joint_type);
    EXPECT_EQ(copy->parent, m->parent);
    EXPECT_EQ(copy->spherical_range, m->spherical_range);
    EXPECT_EQ(copy->collision, m->collision);
    for (int i = 1; i < m->njoints; ++i) {
      EXPECT_TRUE(copy->X_PJ[i].is_approx(m->X_PJ[i], 1e-15));
      EXPECT_NEAR(copy->inertia[i].mass, m->inertia[i].mass, 1e-15 * m->inertia[i].mass);
      EXPECT_LT((copy->inertia[i].h - m->inertia[i].h).norm(), 1e-14);
      EXPECT_LT((copy->inertia[i].I_O - m->inertia[i].I_O).norm(), 1e-14);
    }
  }
}

TEST(ModelEdit, WeldRootFixesTheFreeRootInPlace) {
  const auto m = core::build_human_figure({});
  const auto welded = core::weld_root(m);
  EXPECT_EQ(welded->joint_type[1], core::JointType::kFixed);
  EXPECT_EQ(welded->nv, m->nv - 6);
  EXPECT_EQ(welded->nq, m->nq - 7);
  // at neutral every link is where it was
  core::Data d0(*m), d1(*welded);
  core::forward_kinematics(*m, d0, core::neutral_configuration(*m));
  core::forward_kinematics(*welded, d1, core::neutral_configuration(*welded));
  for (int i = 1; i < m->njoints; ++i) EXPECT_TRUE(d1.X_W[i].is_approx(d0.X_W[i], 1e-15));
  // a fixed root is returned as it is
  const auto arm = manipulator5();
  EXPECT_EQ(core::weld_root(arm).get(), arm.get());
}

}  // namespace
