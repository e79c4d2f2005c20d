// One physics step of human48 (the bundled figure, feet as boxes) standing on the ground, with
// each effect switched on alone and in the combinations a scene uses, ours (sim::World, 1 ms,
// implicit) and MuJoCo's mj_step on the same figure as MJCF (same geoms, a floor plane, 1 ms,
// its default soft contacts) with the matching disable flags, in the same run.
//
// A passive figure sags once gravity acts, so every 200 steps (0.2 s) both restart from the
// standing state; the restart is not timed. MuJoCo cannot skip what a scene does not ask for:
// with every effect disabled mj_step still runs its whole smooth dynamics, which is what
// BM_Step_MuJoCo/none shows.
// Rows: BM_Step/<effects>, BM_Step_MuJoCo/<effects>; "gcf" = gravity + ground contact + friction;
// BM_Step/gcf_dynamic_pins is the standing figure driven by its dynamics-backed pins, and
// BM_Frame60/gcf_dynamic_pins one displayed 60 Hz frame of it (1/60 s of 1 ms steps).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/bench_models.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "sim/placement.hpp"
#include "sim/world.hpp"
#include "tests/fixtures/mjcf_writer.hpp"

namespace {

constexpr int kRestartEvery = 200;

struct Case {
  const char* name;
  sim::Scene scene;
};

std::vector<Case> cases() {
  auto scene = [](std::initializer_list<sim::Effect> effects) {
    sim::Scene s;
    for (sim::Effect e : effects) s.set(e, true);
    return s;
  };
  using E = sim::Effect;
  return {{"none", scene({})},
          {"gravity", scene({E::kGravity})},
          {"ground_contact", scene({E::kGroundContact})},
          {"friction", scene({E::kFriction})},
          {"hard_limits", scene({E::kHardLimits})},
          {"self_collision", scene({E::kSelfCollision})},
          {"gcf", scene({E::kGravity, E::kGroundContact, E::kFriction})},
          {"gcf_limits_self", scene({E::kGravity, E::kGroundContact, E::kFriction, E::kHardLimits,
                                     E::kSelfCollision})}};
}

const std::shared_ptr<const core::Model>& figure() {
  static const auto m = core::build_human_figure({});
  return m;
}

Eigen::VectorXd standing() {
  const core::Model& m = *figure();
  return sim::place_on_ground(m, core::rest_configuration(m), sim::GroundPlane{});
}

// Times world.step(), restarting from the world's present state every kRestartEvery steps.
void time_steps(benchmark::State& state, sim::World& world) {
  const sim::World start = world;
  int k = 0;
  for (auto _ : state) {
    if (++k % kRestartEvery == 0) {
      state.PauseTiming();
      world = start;
      state.ResumeTiming();
    }
    world.step();
  }
  state.counters["contacts"] = static_cast<double>(world.contact_points().size());
}

void step_ours(benchmark::State& state, const sim::Scene& scene) {
  sim::World world;
  world.add_body("human48", figure(), standing());
  world.set_scene(scene);
  time_steps(state, world);
}

std::string mjcf_path(bool self_collision) {
  const std::string path =
      (std::filesystem::temp_directory_path() /
       (self_collision ? "pindrag_sim_bench_self.xml" : "pindrag_sim_bench.xml"))
          .string();
  fixtures::MjcfOptions o;
  o.collision_geoms = o.floor = o.hinge_limits = true;
  o.self_collision = self_collision;
  std::ofstream(path) << fixtures::write_mjcf(*figure(), o);
  return path;
}

void step_mujoco(benchmark::State& state, const sim::Scene& scene) {
  bench::MujocoModel mj(mjcf_path(scene.self_collision));
  if (!mj.m) {
    state.SkipWithError("MuJoCo could not load the figure");
    return;
  }
  int disable = 0;
  if (!scene.gravity) disable |= mjDSBL_GRAVITY;
  if (!scene.ground_contact && !scene.self_collision) disable |= mjDSBL_CONTACT;
  if (!scene.friction) disable |= mjDSBL_FRICTIONLOSS;
  if (!scene.hard_limits) disable |= mjDSBL_LIMIT;
  mj.m->opt.disableflags = disable;
  if (!scene.friction) {
    for (int g = 0; g < mj.m->ngeom; ++g) mj.m->geom_condim[g] = 1;  // frictionless contacts
  }
  // the same standing state: our q is MuJoCo's qpos (free root position, then w x y z)
  const Eigen::VectorXd q = standing();
  for (int i = 0; i < mj.m->nq; ++i) mj.d->qpos[i] = q[i];
  mj_forward(mj.m, mj.d);
  std::vector<double> qpos(mj.d->qpos, mj.d->qpos + mj.m->nq);
  int k = 0;
  for (auto _ : state) {
    if (++k % kRestartEvery == 0) {
      state.PauseTiming();
      mj_resetData(mj.m, mj.d);
      std::copy(qpos.begin(), qpos.end(), mj.d->qpos);
      state.ResumeTiming();
    }
    mj_step(mj.m, mj.d);
  }
  state.counters["contacts"] = mj.d->ncon;
}

// The dynamics-backed pins' scene (Yamane §9.4): human48 standing on level feet in stiff soft
// contact, orientation pins on both feet (which the balance feedback tilts), every joint
// referenced to its standing value, the left hand dragged; its joints are driven at acceleration
// level and its root moves by the contact forces.
sim::World pinned_world() {
  const core::Model& m = *figure();
  sim::WorldSettings settings;
  settings.contact = sim::figure_contact_settings(m.total_mass());
  sim::World world(settings);
  const Eigen::VectorXd q0 =
      sim::standing_configuration(m, core::neutral_configuration(m), sim::GroundPlane{});
  world.add_body("human48", figure(), q0);
  sim::Scene scene;
  scene.gravity = scene.ground_contact = scene.friction = scene.dynamic_pins = true;
  world.set_scene(scene);
  ik::Problem problem;
  ik::add_joint_references(m, q0, problem);
  core::Data data(m);
  core::forward_kinematics(m, data, q0);
  for (const char* foot : {"l_foot", "r_foot"}) {
    const int link = m.link_index(foot);
    problem.add(ik::LinkTask{.role = ik::kPin,
                             .link = link,
                             .target_R_W = core::Quaternion(data.X_W[link].R),
                             .mode = ik::TaskMode::kOrientation});
  }
  const int hand = m.link_index("l_hand");
  problem.add(ik::LinkTask{.role = ik::kDrag, .link = hand, .target_W = data.X_W[hand].p});
  world.set_pin_problem(0, problem);
  return world;
}

void step_pinned(benchmark::State& state) {
  sim::World world = pinned_world();
  time_steps(state, world);
}

// One displayed frame at 60 Hz of the same scene: the world advanced by 1/60 s (16 or 17 steps
// of 1 ms, the remainder carried), as the page's session does once per tick.
void frame_pinned(benchmark::State& state) {
  sim::World world = pinned_world();
  const sim::World start = world;
  int k = 0;
  for (auto _ : state) {
    if (++k % (kRestartEvery / 16 + 1) == 0) {
      state.PauseTiming();
      world = start;
      state.ResumeTiming();
    }
    world.advance(1.0 / 60);
  }
}

const bool registered = [] {
  benchmark::RegisterBenchmark("BM_Step/gcf_dynamic_pins", step_pinned);
  benchmark::RegisterBenchmark("BM_Frame60/gcf_dynamic_pins", frame_pinned)
      ->Unit(benchmark::kMicrosecond);
  for (const Case& c : cases()) {
    benchmark::RegisterBenchmark((std::string("BM_Step/") + c.name).c_str(), step_ours, c.scene);
    benchmark::RegisterBenchmark((std::string("BM_Step_MuJoCo/") + c.name).c_str(), step_mujoco,
                                 c.scene);
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
