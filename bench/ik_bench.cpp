// One pin-and-drag IK step on the human figure at the size Yamane reports (48 DOF, 1 dragged
// link, 5 pins, 20 joint reference rows: 33 ms on a 1 GHz Pentium III), ours against a plain
// dense baseline and KDL's TreeIkSolverVel_wdls in the same run.
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treeiksolvervel_wdls.hpp>

#include "bench/bench_models.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"
#include "ik/pin_hold.hpp"
#include "ik/solver.hpp"

namespace {

using core::Quaternion;
using core::Vector3;

// The scene: a 6-D drag on the right hand, 6-D pins on both feet, the left hand, the head and
// the pelvis, and reference rows on six spherical joints and two hinges (18 + 2 = 20 rows).
struct Scene {
  std::shared_ptr<const core::Model> model = core::build_human_figure({});
  Eigen::VectorXd q0;
  ik::Problem problem;
  Scene() {
    const core::Model& m = *model;
    q0 = core::neutral_configuration(m);
    // a bent, asymmetric pose so nothing starts at a singularity
    for (int i = 2; i < m.njoints; ++i) {
      const int iq = m.idx_q[i];
      if (m.joint_type[i] == core::JointType::kRevolute) q0[iq] = 0.2 * std::sin(i);
      if (m.joint_type[i] == core::JointType::kSpherical)
        core::set_quaternion_at(
            q0, iq,
            Quaternion(Eigen::AngleAxisd(0.15, Vector3(std::sin(i), 1, std::cos(i)).normalized())));
    }
    core::Data d(m);
    core::forward_kinematics(m, d, q0);
    auto pose_of = [&](const char* name) { return d.X_W[m.link_index(name)]; };
    const core::Transform hand = pose_of("r_hand");
    problem.add(ik::LinkTask{.role = ik::kDrag,
                             .link = m.link_index("r_hand"),
                             .target_W = hand.p + Vector3(-0.05, 0.08, 0.1),
                             .target_R_W = Quaternion(hand.R),
                             .mode = ik::TaskMode::kPose});
    for (const char* pin : {"l_foot", "r_foot", "l_hand", "head", "pelvis"}) {
      const core::Transform X = pose_of(pin);
      problem.add(ik::LinkTask{.role = ik::kPin,
                               .link = m.link_index(pin),
                               .target_W = X.p,
                               .target_R_W = Quaternion(X.R),
                               .mode = ik::TaskMode::kPose});
    }
    for (const char* j :
         {"abdomen", "chest", "neck", "l_uarm", "r_uarm", "l_thigh", "l_farm", "r_farm"}) {
      problem.add(ik::JointReferenceTask{.joint = m.link_index(j)});
    }
  }
};

void BM_IkStep(benchmark::State& state) {
  Scene scene;
  const core::Model& m = *scene.model;
  core::Data data(m);
  ik::Solver solver(m);
  Eigen::VectorXd q = scene.q0;
  solver.step(scene.problem, data, q);  // sizes the workspace
  int rows = 0;
  for (auto _ : state) {
    q = scene.q0;
    const ik::Report& r = solver.step(scene.problem, data, q);
    rows = r.lower_rows;
    benchmark::DoNotOptimize(q.data());
  }
  state.counters["lower_rows"] = rows;
  state.counters["top_rows"] = solver.report().top_rows;
  state.counters["range_rows"] = solver.report().range_rows;  // active-set rows for joint ranges
}

// The same step done the plain way: stack the rows, form the N×N null-space projector, and
// solve the lower level by Cholesky of its normal equations (no sparsity, no implicit projector).
void BM_IkStep_Dense(benchmark::State& state) {
  Scene scene;
  const core::Model& m = *scene.model;
  const int n = m.nv;
  core::Data data(m);
  const ik::SolverSettings s;
  Eigen::MatrixXd J1(6, n), J2(50, n), W(n, n), S(50, n), A(n, n);
  Eigen::VectorXd v1(6), v2(50), x(n), q(m.nq);
  for (auto _ : state) {
    q = scene.q0;
    core::compute_joint_jacobians(m, data, q);
    int r1 = 0, r2 = 0;
    for (const auto& e : scene.problem.entries()) {
      if (const auto* t = std::get_if<ik::LinkTask>(&e.task)) {
        if (t->role == ik::kDrag) {
          ik::fill_link_task(m, data, *t, s.drag_gain, {}, J1.middleRows(r1, 6), v1.segment(r1, 6));
          r1 += 6;
        } else {
          ik::fill_link_task(m, data, *t, s.pin_gain, {}, J2.middleRows(r2, 6), v2.segment(r2, 6));
          r2 += 6;
        }
      } else if (const auto* j = std::get_if<ik::JointReferenceTask>(&e.task)) {
        const int rows = ik::task_rows(m, *j);
        ik::fill_reference_task(m, q, *j, s.reference_gain, {}, J2.middleRows(r2, rows),
                                v2.segment(r2, rows));
        r2 += rows;
      }
    }
    // top: pseudoinverse, explicit projector W = E − J1⁺ J1
    const Eigen::MatrixXd J1pinv =
        J1.transpose() * (J1 * J1.transpose()).llt().solve(Eigen::MatrixXd::Identity(6, 6));
    x = J1pinv * v1;
    W = Eigen::MatrixXd::Identity(n, n) - J1pinv * J1;
    // lower: S = J2 W, y = (SᵀS + kE)⁻¹ Sᵀ (v2 − J2 x)
    S = J2.topRows(r2) * W;
    A = S.topRows(r2).transpose() * S.topRows(r2) + s.damping * Eigen::MatrixXd::Identity(n, n);
    x += W * A.llt().solve(S.topRows(r2).transpose() * (v2.head(r2) - J2.topRows(r2) * x));
    core::integrate(m, q, x, s.dt, q);
    benchmark::DoNotOptimize(q.data());
  }
}

// KDL's weighted damped least squares over the tree: the drag and the five pins as endpoint
// twists on the benchmark twin (human48_float6.urdf). KDL has no priority levels and no joint
// reference rows, so it solves 36 rows in one level.
void BM_IkStep_KDL(benchmark::State& state) {
  const std::string dir = bench::bench_models_dir();
  KDL::Tree tree;
  if (dir.empty() || !bench::load_kdl_tree(dir + "/human48_float6.urdf", tree)) {
    return state.SkipWithError("human48_float6.urdf not available");
  }
  const std::vector<std::string> tips = {"r_hand", "l_foot", "r_foot", "l_hand", "head", "pelvis"};
  KDL::TreeIkSolverVel_wdls solver(tree, tips);
  solver.setLambda(std::sqrt(ik::kDefaultDamping));
  KDL::TreeFkSolverPos_recursive fk(tree);
  KDL::JntArray q(tree.getNrOfJoints()), qdot(tree.getNrOfJoints());
  for (unsigned j = 0; j < q.rows(); ++j) q(j) = 0.2 * std::sin(j);
  KDL::Twists twists;
  KDL::Frame f;
  for (const auto& t : tips) twists[t] = KDL::Twist();
  for (auto _ : state) {
    for (const auto& t : tips) {
      fk.JntToCart(q, f, t);
      twists[t] = KDL::Twist(KDL::Vector(0.01, 0.0, 0.0), KDL::Vector(0.0, 0.0, 0.0));
    }
    solver.CartToJnt(q, twists, qdot);
    benchmark::DoNotOptimize(qdot.data.data());
  }
}

// One posing frame of a squat at its hardest, the first: both feet pinned (6-D), the pelvis
// dragged 8.3 mm down (0.5 m/s at 60 Hz) from the rest pose, knees almost straight. Hard pins:
// the step (pins on level 1, the drag on level 3) and ik::PinHold's corrections; soft pins: the
// book's step alone (the drag exact, pins giving way). The counters give the pins' error after
// the frame (mm) and the corrections taken.
void squat_frame(benchmark::State& state, bool hard) {
  const auto model = core::build_human_figure({});
  const core::Model& m = *model;
  const Eigen::VectorXd q0 = core::rest_configuration(m);
  core::Data data(m);
  core::forward_kinematics(m, data, q0);
  ik::SolverSettings settings;
  settings.hard_pins = hard;
  ik::Problem problem;
  for (const char* foot : {"l_foot", "r_foot"}) {
    const core::Transform X = data.X_W[m.link_index(foot)];
    problem.add(ik::LinkTask{.role = ik::kPin,
                             .link = m.link_index(foot),
                             .target_W = X.p,
                             .target_R_W = Quaternion(X.R),
                             .mode = ik::TaskMode::kPose},
                ik::pin_priority(settings));
  }
  const Vector3 down(0, -0.5 / 60, 0);
  ik::add_drag(
      ik::LinkTask{
          .role = ik::kDrag, .link = 1, .target_W = data.X_W[1].p + down, .velocity_W = down * 60},
      settings, problem);
  ik::Solver solver(m, settings);
  ik::PinHold hold(m);
  Eigen::VectorXd q = q0;
  int corrections = 0;
  for (auto _ : state) {
    q = q0;
    solver.step(problem, data, q);
    if (hard) corrections = hold.hold(settings, problem, data, q).corrections;
    benchmark::DoNotOptimize(q.data());
  }
  double pin_error = 0;
  for (const auto& e : problem.entries()) {
    if (const auto* t = std::get_if<ik::LinkTask>(&e.task); t && t->role == ik::kPin) {
      pin_error = std::max(pin_error, ik::link_task_error(data, *t).position);
    }
  }
  state.counters["pin_error_mm"] = 1e3 * pin_error;
  state.counters["corrections"] = corrections;
}

BENCHMARK(BM_IkStep)->Name("BM_IkStep/human48_p5_j20");
BENCHMARK_CAPTURE(squat_frame, hard_pins, true)->Name("BM_SquatFrame/human48_hard_pins");
BENCHMARK_CAPTURE(squat_frame, soft_pins, false)->Name("BM_SquatFrame/human48_soft_pins");
BENCHMARK(BM_IkStep_Dense)->Name("BM_IkStep_Dense/human48_p5_j20");
BENCHMARK(BM_IkStep_KDL)->Name("BM_IkStep_KDL/human48_p5_j20");

}  // namespace

BENCHMARK_MAIN();
