// Physical checks of the dynamics: conservation laws and closed-form pendulums.
#include <gtest/gtest.h>

#include <cmath>

#include "core/aba.hpp"
#include "core/centroidal.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/integrators.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using namespace core;

// Simulates with RK4 and zero torque; returns the largest |E(t) − E(0)| / E(0).
double energy_drift(const Model& m, Eigen::VectorXd q, Eigen::VectorXd v, double dt, double T) {
  Data d(m);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(m.nv);
  auto energy = [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv) {
    forward_kinematics(m, d, qq, vv);
    return kinetic_energy(m, d) + potential_energy(m, d);
  };
  const double E0 = energy(q, v);
  Rk4Workspace w;
  double worst = 0;
  const int steps = static_cast<int>(std::lround(T / dt));
  for (int k = 0; k < steps; ++k) {
    rk4_step(
        m, q, v, dt,
        [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv, Eigen::VectorXd& a) {
          a = aba(m, d, qq, vv, tau);
        },
        w);
    worst = std::max(worst, std::abs(energy(q, v) - E0) / std::abs(E0));
  }
  return worst;
}

TEST(Physics, EnergyIsConservedInFreeMotionAndDriftShrinksWithTheStep) {
  const auto m = fixtures::branching_tree(Vector3::Zero());
  const Eigen::VectorXd q = random_configuration(*m, 21);
  const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, 22));
  const double coarse = energy_drift(*m, q, v, 1e-3, 1.0);
  const double fine = energy_drift(*m, q, v, 1e-4, 1.0);
  EXPECT_LT(fine, 1e-9);
  EXPECT_LT(fine, coarse / 100.0) << "coarse " << coarse << " fine " << fine;
}

TEST(Physics, EnergyIsConservedUnderGravity) {
  const auto m = fixtures::branching_tree();
  const Eigen::VectorXd q = random_configuration(*m, 31);
  const Eigen::VectorXd v = difference(*m, q, random_configuration(*m, 32));
  EXPECT_LT(energy_drift(*m, q, v, 1e-4, 1.0), 1e-8);
}

TEST(Physics, MomentumOfAFreeFloatingFigureIsConserved) {
  const auto m = fixtures::branching_tree(Vector3::Zero());
  Data d(*m);
  Eigen::VectorXd q = random_configuration(*m, 41);
  Eigen::VectorXd v = difference(*m, q, random_configuration(*m, 42));
  // internal joint torques only (small: the wrist is light): they cannot change the momentum
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(m->nv);
  tau.tail(m->nv - 6) = Eigen::VectorXd::LinSpaced(m->nv - 6, -0.01, 0.01);
  forward_kinematics(*m, d, q, v);
  const Force h0 = centroidal_momentum(*m, d);
  // the centroidal momentum matrix gives the same momentum
  compute_joint_jacobians(*m, d, q);
  const Vector6 h_matrix = centroidal_momentum_matrix(*m, d) * v;
  EXPECT_LT((h_matrix - h0.vector()).norm(), 1e-12 * (1 + h0.vector().norm()));
  Rk4Workspace w;
  for (int k = 0; k < 5000; ++k) {
    rk4_step(
        *m, q, v, 2e-4,
        [&](const Eigen::VectorXd& qq, const Eigen::VectorXd& vv, Eigen::VectorXd& a) {
          a = aba(*m, d, qq, vv, tau);
        },
        w);
  }
  forward_kinematics(*m, d, q, v);
  const Force h1 = centroidal_momentum(*m, d);
  EXPECT_LT((h1.linear - h0.linear).norm(), 1e-9 * (1 + h0.linear.norm()));
  EXPECT_LT((h1.angular - h0.angular).norm(), 1e-9 * (1 + h0.angular.norm()));
}

// One revolute link about z hanging along −y from the world.
std::shared_ptr<const Model> pendulum(double mass, double l, double I_zz) {
  ModelBuilder b("pendulum");
  LinkSpec link;
  link.name = "bob";
  link.joint.type = JointType::kRevolute;
  link.joint.axis = Vector3::UnitZ();
  link.mass = mass;
  link.com = Vector3(0, -l, 0);
  link.I_com = Vector3(I_zz / 2, I_zz / 2, I_zz).asDiagonal();
  b.add_link(link);
  return b.finalize();
}

TEST(Physics, PendulumMatchesItsClosedForm) {
  const double mass = 2.0, l = 0.7, I_zz = 0.05, g = 9.81;
  const auto m = pendulum(mass, l, I_zz);
  Data d(*m);
  for (double theta : {-2.0, -0.3, 0.0, 0.5, 1.2, 3.0}) {
    Eigen::VectorXd q(1), v(1), tau(1);
    q << theta;
    v << 1.7;
    tau << 0.4;
    // (I + m l²) θ̈ = τ − m g l sin θ
    const double expected = (0.4 - mass * g * l * std::sin(theta)) / (I_zz + mass * l * l);
    EXPECT_NEAR(aba(*m, d, q, v, tau)[0], expected, 1e-12) << theta;
  }
}

TEST(Physics, DoublePendulumMatchesItsClosedForm) {
  // point masses m1, m2 on massless rods l1, l2; θ1, θ2 absolute angles from the downward vertical
  const double m1 = 1.3, m2 = 0.8, l1 = 0.9, l2 = 0.6, g = 9.81;
  ModelBuilder b("double_pendulum");
  LinkSpec a;
  a.name = "upper";
  a.joint.type = JointType::kRevolute;
  a.mass = m1;
  a.com = Vector3(0, -l1, 0);
  b.add_link(a);
  LinkSpec c;
  c.name = "lower";
  c.parent = "upper";
  c.joint.type = JointType::kRevolute;
  c.joint.X_PJ.p = Vector3(0, -l1, 0);
  c.mass = m2;
  c.com = Vector3(0, -l2, 0);
  b.add_link(c);
  const auto m = b.finalize();
  Data d(*m);
  for (int trial = 0; trial < 5; ++trial) {
    const double t1 = -1.0 + 0.7 * trial, t2 = 0.4 - 0.5 * trial;
    const double w1 = 0.9 - 0.3 * trial, w2 = -1.1 + 0.6 * trial;
    // Lagrange equations in absolute angles:
    //  (m1+m2) l1 θ1'' + m2 l2 cos(θ1−θ2) θ2'' = −m2 l2 θ2'² sin(θ1−θ2) − (m1+m2) g sin θ1
    //  l1 cos(θ1−θ2) θ1'' + l2 θ2''          =  l1 θ1'² sin(θ1−θ2) − g sin θ2
    Eigen::Matrix2d A;
    A << (m1 + m2) * l1, m2 * l2 * std::cos(t1 - t2), l1 * std::cos(t1 - t2), l2;
    const Eigen::Vector2d rhs(-m2 * l2 * w2 * w2 * std::sin(t1 - t2) - (m1 + m2) * g * std::sin(t1),
                              l1 * w1 * w1 * std::sin(t1 - t2) - g * std::sin(t2));
    const Eigen::Vector2d abs_dd = A.lu().solve(rhs);
    // joint 2 is relative: q2 = θ2 − θ1
    Eigen::VectorXd q(2), v(2);
    q << t1, t2 - t1;
    v << w1, w2 - w1;
    const Eigen::VectorXd qdd = aba(*m, d, q, v, Eigen::VectorXd::Zero(2));
    EXPECT_NEAR(qdd[0], abs_dd[0], 1e-11) << trial;
    EXPECT_NEAR(qdd[1], abs_dd[1] - abs_dd[0], 1e-11) << trial;
  }
}

}  // namespace
