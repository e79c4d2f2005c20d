// Forward kinematics and Jacobians of every link, ours and MuJoCo's and KDL's on the same models.
// Names: BM_<Operation>/<model>, BM_<Operation>_<Peer>/<model>.
#include <benchmark/benchmark.h>

#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treejnttojacsolver.hpp>

#include "bench/bench_models.hpp"
#include "core/configuration.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"

namespace {

using bench::BenchModel;

constexpr int kConfigurations = 16;  // cycled so no two consecutive calls see the same input

std::vector<Eigen::VectorXd> configurations(const core::Model& m) {
  std::vector<Eigen::VectorXd> qs;
  for (int k = 0; k < kConfigurations; ++k) qs.push_back(core::random_configuration(m, 1000 + k));
  return qs;
}

void fk(benchmark::State& state, const BenchModel& bm) {
  core::Data data(*bm.model);
  const auto qs = configurations(*bm.model);
  int k = 0;
  for (auto _ : state) {
    core::forward_kinematics(*bm.model, data, qs[k++ % kConfigurations]);
    benchmark::DoNotOptimize(data.X_W.back());
  }
}

// FK plus every joint's motion axes in world: each link's Jacobian is its ancestors' columns
void fk_jacobians(benchmark::State& state, const BenchModel& bm) {
  core::Data data(*bm.model);
  const auto qs = configurations(*bm.model);
  int k = 0;
  for (auto _ : state) {
    core::compute_joint_jacobians(*bm.model, data, qs[k++ % kConfigurations]);
    benchmark::DoNotOptimize(data.J.data());
  }
}

// as above, and every link's dense 6 x nv Jacobian at its origin (what mj_jacBody per body does)
void fk_link_jacobians_of(benchmark::State& state,
                          const core::Model& m,
                          const std::vector<core::LinkJacobians::Point>& points) {
  core::Data data(m);
  const auto qs = configurations(m);
  core::LinkJacobians J(m, points);
  int k = 0;
  for (auto _ : state) {
    core::compute_joint_jacobians(m, data, qs[k++ % kConfigurations]);
    J.update(m, data);
    benchmark::DoNotOptimize(J[J.size() - 1].linear.data());
  }
  state.counters["links"] = static_cast<double>(points.size());
}

// every link of the model, massless links between the axes of a multi-axis joint included
void fk_link_jacobians(benchmark::State& state, const BenchModel& bm) {
  std::vector<core::LinkJacobians::Point> points;
  for (int i = 1; i < bm.model->njoints; ++i) points.push_back({i, core::Vector3::Zero()});
  fk_link_jacobians_of(state, *bm.model, points);
}

// the links that are the MuJoCo twin's bodies (by name): the same output as mj_jacBody per body
void fk_body_jacobians(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  std::vector<core::LinkJacobians::Point> points;
  for (int b = 1; b < mj.m->nbody; ++b) {
    const char* name = mj_id2name(mj.m, mjOBJ_BODY, b);
    const int link = name ? bm.model->link_index(name) : -1;
    if (link < 1) return state.SkipWithError("a MuJoCo body has no link of the same name");
    points.push_back({link, core::Vector3::Zero()});
  }
  fk_link_jacobians_of(state, *bm.model, points);
}

void randomize_mujoco(const mjModel* m, std::vector<std::vector<double>>& qpos) {
  unsigned seed = 7;
  for (int k = 0; k < kConfigurations; ++k) {
    std::vector<double> q(m->qpos0, m->qpos0 + m->nq);
    for (int j = 0; j < m->njnt; ++j) {
      const int a = m->jnt_qposadr[j];
      seed = seed * 1103515245u + 12345u;
      const double u = (seed >> 8) / double(1 << 24) - 0.5;
      if (m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE) q[a] = 2.0 * u;
    }
    qpos.push_back(q);
  }
}

void fk_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  std::vector<std::vector<double>> qpos;
  randomize_mujoco(mj.m, qpos);
  int k = 0;
  for (auto _ : state) {
    std::copy(qpos[k % kConfigurations].begin(), qpos[k % kConfigurations].end(), mj.d->qpos);
    ++k;
    mj_kinematics(mj.m, mj.d);
    benchmark::DoNotOptimize(mj.d->xpos);
  }
}

void fk_jacobians_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  std::vector<std::vector<double>> qpos;
  randomize_mujoco(mj.m, qpos);
  std::vector<double> jacp(3 * mj.m->nv * mj.m->nbody), jacr(3 * mj.m->nv * mj.m->nbody);
  int k = 0;
  for (auto _ : state) {
    std::copy(qpos[k % kConfigurations].begin(), qpos[k % kConfigurations].end(), mj.d->qpos);
    ++k;
    mj_kinematics(mj.m, mj.d);
    mj_comPos(mj.m, mj.d);
    for (int b = 1; b < mj.m->nbody; ++b) {
      mj_jacBody(mj.m, mj.d, &jacp[3 * mj.m->nv * b], &jacr[3 * mj.m->nv * b], b);
    }
    benchmark::DoNotOptimize(jacp.data());
  }
}

struct KdlSetup {
  KDL::Tree tree;
  std::vector<std::string> segments;
  std::vector<KDL::JntArray> qs;
  bool ok = false;
  explicit KdlSetup(const std::string& urdf) {
    ok = bench::load_kdl_tree(urdf, tree);
    if (!ok) return;
    for (const auto& [name, element] : tree.getSegments()) {
      if (name != tree.getRootSegment()->first) segments.push_back(name);
    }
    for (int k = 0; k < kConfigurations; ++k) {
      KDL::JntArray q(tree.getNrOfJoints());
      for (unsigned j = 0; j < q.rows(); ++j) q(j) = 0.3 * std::sin(1.7 * j + k);
      qs.push_back(q);
    }
  }
};

void fk_kdl(benchmark::State& state, const BenchModel& bm) {
  KdlSetup kdl(bm.kdl_urdf);
  if (!kdl.ok) return state.SkipWithError("KDL could not load the model");
  KDL::TreeFkSolverPos_recursive solver(kdl.tree);
  KDL::Frame f;
  int k = 0;
  for (auto _ : state) {
    const KDL::JntArray& q = kdl.qs[k++ % kConfigurations];
    for (const std::string& s : kdl.segments) solver.JntToCart(q, f, s);
    benchmark::DoNotOptimize(f);
  }
}

void fk_jacobians_kdl(benchmark::State& state, const BenchModel& bm) {
  KdlSetup kdl(bm.kdl_urdf);
  if (!kdl.ok) return state.SkipWithError("KDL could not load the model");
  KDL::TreeFkSolverPos_recursive fk_solver(kdl.tree);
  KDL::TreeJntToJacSolver jac_solver(kdl.tree);
  KDL::Frame f;
  KDL::Jacobian J(kdl.tree.getNrOfJoints());
  int k = 0;
  for (auto _ : state) {
    const KDL::JntArray& q = kdl.qs[k++ % kConfigurations];
    for (const std::string& s : kdl.segments) {
      fk_solver.JntToCart(q, f, s);
      jac_solver.JntToJac(q, J, s);
    }
    benchmark::DoNotOptimize(J.data.data());
  }
}

const bool registered = [] {
  for (const BenchModel& bm : bench::models()) {
    const std::string n = "/" + bm.name;
    benchmark::RegisterBenchmark(("BM_Fk" + n).c_str(), fk, bm);
    benchmark::RegisterBenchmark(("BM_FkJacobians" + n).c_str(), fk_jacobians, bm);
    benchmark::RegisterBenchmark(("BM_FkLinkJacobians" + n).c_str(), fk_link_jacobians, bm);
    if (!bm.mujoco_xml.empty()) {
      benchmark::RegisterBenchmark(("BM_Fk_MuJoCo" + n).c_str(), fk_mujoco, bm);
      benchmark::RegisterBenchmark(("BM_FkBodyJacobians" + n).c_str(), fk_body_jacobians, bm);
      benchmark::RegisterBenchmark(("BM_FkJacobians_MuJoCo" + n).c_str(), fk_jacobians_mujoco, bm);
    }
    if (!bm.kdl_urdf.empty()) {
      benchmark::RegisterBenchmark(("BM_Fk_KDL" + n).c_str(), fk_kdl, bm);
      benchmark::RegisterBenchmark(("BM_FkJacobians_KDL" + n).c_str(), fk_jacobians_kdl, bm);
    }
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
