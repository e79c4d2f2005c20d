// Dynamics: RNEA, CRBA, ABA, CRBA + sparse LTDL factorization + solve, and the inverse
// operational-space inertia Φ, ours and MuJoCo's and KDL's on the same models.
// Names: BM_<Operation>/<model>, BM_<Operation>_<Peer>/<model>. What each peer row times:
//   BM_Rnea_MuJoCo      mj_kinematics + mj_comPos + mj_comVel + mj_rne(flg_acc = 1)
//                       (ours recomputes the joint transforms and velocities inside rnea() too)
//   BM_Crba_MuJoCo      mj_kinematics + mj_comPos + mj_crb (sparse qM, no mj_fullM)
//   BM_CrbaLtdl_MuJoCo  BM_Crba_MuJoCo + mj_factorM + mj_solveM (one right-hand side)
//   BM_Aba_MuJoCo       mj_forward with constraints, equality, friction loss, limits, contacts,
//                       passive forces, actuation and sensors disabled: kinematics, comPos, crb,
//                       factorM, comVel, rne bias, solveM (MuJoCo's forward dynamics is CRBA-based;
//                       it has no ABA)
//   BM_Rnea_KDL         ChainIdSolver_RNE on chains; TreeIdSolver_RNE on the float6 twin of a
//                       figure (its free root as six 1-DOF joints)
//   BM_Crba_KDL         ChainDynParam::JntToMass (chains only: KDL has no tree mass matrix)
#include <benchmark/benchmark.h>

#include <kdl/chaindynparam.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>

#include "bench/bench_models.hpp"
#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/jacobian.hpp"
#include "core/osim.hpp"
#include "core/rnea.hpp"

namespace {

using bench::BenchModel;

constexpr int kStates = 16;  // cycled so no two consecutive calls see the same input

struct States {
  std::vector<Eigen::VectorXd> q, v, a, tau;
  explicit States(const core::Model& m) {
    for (int k = 0; k < kStates; ++k) {
      q.push_back(core::random_configuration(m, 1000 + k));
      v.push_back(core::difference(m, q.back(), core::random_configuration(m, 2000 + k)));
      a.push_back(core::difference(m, q.back(), core::random_configuration(m, 3000 + k)));
      tau.push_back(10.0 * core::difference(m, q.back(), core::random_configuration(m, 4000 + k)));
    }
  }
};

void time_rnea(benchmark::State& state, const BenchModel& bm) {
  const core::Model& m = *bm.model;
  core::Data data(m);
  const States s(m);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    benchmark::DoNotOptimize(core::rnea(m, data, s.q[i], s.v[i], s.a[i]).data());
  }
}

void time_crba(benchmark::State& state, const BenchModel& bm) {
  const core::Model& m = *bm.model;
  core::Data data(m);
  const States s(m);
  int k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(core::crba(m, data, s.q[k++ % kStates]).data());
}

void time_aba(benchmark::State& state, const BenchModel& bm) {
  const core::Model& m = *bm.model;
  core::Data data(m);
  const States s(m);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    benchmark::DoNotOptimize(core::aba(m, data, s.q[i], s.v[i], s.tau[i]).data());
  }
}

// H from CRBA, H = Lᵀ D L, one solve (as BM_CrbaLtdl_MuJoCo: no bias forces)
void crba_ltdl(benchmark::State& state, const BenchModel& bm) {
  const core::Model& m = *bm.model;
  core::Data data(m);
  const States s(m);
  Eigen::VectorXd x(m.nv);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    core::crba(m, data, s.q[i]);
    core::factorize_mass_matrix(m, data);
    x = s.tau[i];
    core::solve_mass_matrix(m, data, x);
    benchmark::DoNotOptimize(x.data());
  }
}

// Φ = J H⁻¹ Jᵀ for the figure's hands, feet, head and pelvis (6-D handles) or a chain's tip
std::vector<core::Handle> handles(const core::Model& m) {
  std::vector<core::Handle> out;
  for (const char* link : {"l_hand", "r_hand", "l_foot", "r_foot", "head", "pelvis"}) {
    if (const int i = m.link_index(link); i > 0) out.push_back({i, core::Vector3::Zero(), true});
  }
  if (out.empty()) out.push_back({m.njoints - 1, core::Vector3::Zero(), true});
  return out;
}

void osim(benchmark::State& state, const BenchModel& bm) {
  const core::Model& m = *bm.model;
  core::Data data(m);
  const States s(m);
  const std::vector<core::Handle> h = handles(m);
  core::OsimWorkspace ws;
  Eigen::MatrixXd Phi;
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    core::compute_joint_jacobians(m, data, s.q[i]);
    core::crba(m, data, s.q[i]);
    core::factorize_mass_matrix(m, data);
    core::inverse_operational_inertia(m, data, h, ws, Phi);
    benchmark::DoNotOptimize(Phi.data());
  }
  state.counters["handles"] = static_cast<double>(h.size());
}

// ------------------------------------------------------------------------------------------------
// MuJoCo

struct MujocoStates {
  std::vector<std::vector<double>> qpos, qvel, qacc, qfrc;
  explicit MujocoStates(const mjModel* m) {
    unsigned seed = 7;
    auto uniform = [&] {
      seed = seed * 1103515245u + 12345u;
      return (seed >> 8) / double(1 << 24) - 0.5;
    };
    for (int k = 0; k < kStates; ++k) {
      std::vector<double> q(m->qpos0, m->qpos0 + m->nq);
      for (int j = 0; j < m->njnt; ++j) {
        const int a = m->jnt_qposadr[j];
        if (m->jnt_type[j] == mjJNT_HINGE || m->jnt_type[j] == mjJNT_SLIDE) q[a] = 2.0 * uniform();
        if (m->jnt_type[j] == mjJNT_FREE || m->jnt_type[j] == mjJNT_BALL) {
          const int o = m->jnt_type[j] == mjJNT_FREE ? a + 3 : a;
          mjtNum* r = &q[o];
          for (int c = 0; c < 4; ++c) r[c] = uniform();
          mju_normalize4(r);
        }
      }
      qpos.push_back(q);
      auto vec = [&](double scale) {
        std::vector<double> x(m->nv);
        for (double& e : x) e = scale * uniform();
        return x;
      };
      qvel.push_back(vec(2));
      qacc.push_back(vec(6));
      qfrc.push_back(vec(20));
    }
  }
};

void set_state(const MujocoStates& s, int i, bench::MujocoModel& mj) {
  std::copy(s.qpos[i].begin(), s.qpos[i].end(), mj.d->qpos);
  std::copy(s.qvel[i].begin(), s.qvel[i].end(), mj.d->qvel);
}

void rnea_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  const MujocoStates s(mj.m);
  std::vector<double> tau(mj.m->nv);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    set_state(s, i, mj);
    std::copy(s.qacc[i].begin(), s.qacc[i].end(), mj.d->qacc);
    mj_kinematics(mj.m, mj.d);
    mj_comPos(mj.m, mj.d);
    mj_comVel(mj.m, mj.d);
    mj_rne(mj.m, mj.d, 1, tau.data());
    benchmark::DoNotOptimize(tau.data());
  }
}

void crba_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  const MujocoStates s(mj.m);
  int k = 0;
  for (auto _ : state) {
    set_state(s, k++ % kStates, mj);
    mj_kinematics(mj.m, mj.d);
    mj_comPos(mj.m, mj.d);
    mj_crb(mj.m, mj.d);
    benchmark::DoNotOptimize(mj.d->qM);
  }
}

void crba_ltdl_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  const MujocoStates s(mj.m);
  std::vector<double> x(mj.m->nv);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    set_state(s, i, mj);
    mj_kinematics(mj.m, mj.d);
    mj_comPos(mj.m, mj.d);
    mj_crb(mj.m, mj.d);
    mj_factorM(mj.m, mj.d);
    mj_solveM(mj.m, mj.d, x.data(), s.qfrc[i].data(), 1);
    benchmark::DoNotOptimize(x.data());
  }
}

void aba_mujoco(benchmark::State& state, const BenchModel& bm) {
  bench::MujocoModel mj(bm.mujoco_xml);
  if (!mj.m) return state.SkipWithError("MuJoCo could not load the model");
  mj.m->opt.disableflags |= mjDSBL_CONSTRAINT | mjDSBL_EQUALITY | mjDSBL_FRICTIONLOSS |
                            mjDSBL_LIMIT | mjDSBL_CONTACT | mjDSBL_PASSIVE | mjDSBL_ACTUATION |
                            mjDSBL_SENSOR;
  const MujocoStates s(mj.m);
  int k = 0;
  for (auto _ : state) {
    const int i = k++ % kStates;
    set_state(s, i, mj);
    std::copy(s.qfrc[i].begin(), s.qfrc[i].end(), mj.d->qfrc_applied);
    mj_forward(mj.m, mj.d);
    benchmark::DoNotOptimize(mj.d->qacc);
  }
}

// ------------------------------------------------------------------------------------------------
// KDL

struct KdlSetup {
  KDL::Tree tree;
  KDL::Chain chain;  // root to the deepest leaf; the whole model when it is a chain
  bool ok = false, is_chain = false;
  std::vector<KDL::JntArray> q, v, a;
  explicit KdlSetup(const std::string& urdf) {
    if (!bench::load_kdl_tree(urdf, tree)) return;
    ok = true;
    // a chain when every segment has at most one child
    is_chain = true;
    std::string tip = tree.getRootSegment()->first;
    for (const auto& [name, element] : tree.getSegments()) {
      if (GetTreeElementChildren(element).size() > 1) is_chain = false;
      if (GetTreeElementChildren(element).empty()) tip = name;
    }
    if (is_chain) tree.getChain(tree.getRootSegment()->first, tip, chain);
    const unsigned n = tree.getNrOfJoints();
    for (int k = 0; k < kStates; ++k) {
      KDL::JntArray x(n), y(n), z(n);
      for (unsigned j = 0; j < n; ++j) {
        x(j) = 0.3 * std::sin(1.7 * j + k);
        y(j) = std::cos(0.9 * j + k);
        z(j) = 3 * std::sin(0.4 * j - k);
      }
      q.push_back(x);
      v.push_back(y);
      a.push_back(z);
    }
  }
};

const KDL::Vector kGravity(0, 0, -9.81);

void rnea_kdl(benchmark::State& state, const BenchModel& bm) {
  KdlSetup kdl(bm.kdl_urdf);
  if (!kdl.ok) return state.SkipWithError("KDL could not load the model");
  KDL::JntArray tau(kdl.tree.getNrOfJoints());
  int k = 0;
  if (kdl.is_chain) {
    KDL::ChainIdSolver_RNE solver(kdl.chain, kGravity);
    const KDL::Wrenches f(kdl.chain.getNrOfSegments(), KDL::Wrench::Zero());
    for (auto _ : state) {
      const int i = k++ % kStates;
      solver.CartToJnt(kdl.q[i], kdl.v[i], kdl.a[i], f, tau);
      benchmark::DoNotOptimize(tau.data.data());
    }
  } else {
    KDL::TreeIdSolver_RNE solver(kdl.tree, kGravity);
    const KDL::WrenchMap f;
    for (auto _ : state) {
      const int i = k++ % kStates;
      solver.CartToJnt(kdl.q[i], kdl.v[i], kdl.a[i], f, tau);
      benchmark::DoNotOptimize(tau.data.data());
    }
  }
}

void crba_kdl(benchmark::State& state, const BenchModel& bm) {
  KdlSetup kdl(bm.kdl_urdf);
  if (!kdl.ok || !kdl.is_chain) return state.SkipWithError("KDL has no tree mass matrix");
  KDL::ChainDynParam solver(kdl.chain, kGravity);
  KDL::JntSpaceInertiaMatrix H(kdl.chain.getNrOfJoints());
  int k = 0;
  for (auto _ : state) {
    solver.JntToMass(kdl.q[k++ % kStates], H);
    benchmark::DoNotOptimize(H.data.data());
  }
}

const bool registered = [] {
  for (const BenchModel& bm : bench::models()) {
    const std::string n = "/" + bm.name;
    benchmark::RegisterBenchmark(("BM_Rnea" + n).c_str(), time_rnea, bm);
    benchmark::RegisterBenchmark(("BM_Crba" + n).c_str(), time_crba, bm);
    benchmark::RegisterBenchmark(("BM_Aba" + n).c_str(), time_aba, bm);
    benchmark::RegisterBenchmark(("BM_CrbaLtdl" + n).c_str(), crba_ltdl, bm);
    benchmark::RegisterBenchmark(("BM_Osim" + n).c_str(), osim, bm);
    if (!bm.mujoco_xml.empty()) {
      benchmark::RegisterBenchmark(("BM_Rnea_MuJoCo" + n).c_str(), rnea_mujoco, bm);
      benchmark::RegisterBenchmark(("BM_Crba_MuJoCo" + n).c_str(), crba_mujoco, bm);
      benchmark::RegisterBenchmark(("BM_CrbaLtdl_MuJoCo" + n).c_str(), crba_ltdl_mujoco, bm);
      benchmark::RegisterBenchmark(("BM_Aba_MuJoCo" + n).c_str(), aba_mujoco, bm);
    }
    if (!bm.kdl_urdf.empty()) {
      benchmark::RegisterBenchmark(("BM_Rnea_KDL" + n).c_str(), rnea_kdl, bm);
      if (bm.name.rfind("chain", 0) == 0) {
        benchmark::RegisterBenchmark(("BM_Crba_KDL" + n).c_str(), crba_kdl, bm);
      }
    }
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
