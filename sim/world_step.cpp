// The step pipeline of sim::World: which stages run, in what order, for each integrator.
#include <cmath>

#include "core/configuration.hpp"
#include "core/integrators.hpp"
#include "core/kinematics.hpp"
#include "sim/world.hpp"

namespace sim {

void World::step_euler() {
  bool pins = false;
  for (int b = 0; b < body_count(); ++b) {
    Work& w = work_[b];
    w.mass_matrix_ready = false;
    w.handles.clear();
    w.pinned = false;
    w.falling = false;
    pins = pins || has_pins(b);
  }
  points_.clear();
  pairs_.clear();
  point_forces_.clear();
  next_anchors_.clear();
  StageClock clock(counters_.timers);
  if (scene_.contacts() || pins) {
    run_kinematics();
    clock.lap(TimedPart::kKinematics);
  }
  if (pins) {
    prepare_fallen();
    clock.lap(TimedPart::kDynamicPins);
  }
  if (scene_.contacts()) {
    run_collision_search();  // times its two searches itself
    clock.skip();
    if (!points_.empty()) {
      run_contact_forces();
      if (settings_.integrator == Integrator::kImplicit) {
        run_implicit_contact();
      } else {
        for (ContactPair& p : pairs_) p.wrench = p.wrench0;
      }
      clock.lap(TimedPart::kContactForces);
    }
  }
  if (pins) {
    run_dynamic_pins();
    clock.lap(TimedPart::kDynamicPins);
  }
  run_forward_dynamics();
  clock.lap(TimedPart::kDynamics);
  if (scene_.hard_limits) {
    run_limit_projection();
    clock.lap(TimedPart::kLimits);
  }
  run_integration();
  keep_anchors();
  clock.lap(TimedPart::kIntegration);
}

void World::step_rk4() {
  // classical Runge–Kutta on (q, v) in quaternion-embedding coordinates (renormalized at the
  // end), contact forces explicit at every stage with the friction anchors of the step's start
  static constexpr double kStage[4] = {0.0, 0.5, 0.5, 1.0};
  const double h = settings_.step;
  const int nb = body_count();
  rk_q0_.resize(nb);
  rk_v0_.resize(nb);
  for (int s = 0; s < 4; ++s) {
    rk_kq_[s].resize(nb);
    rk_kv_[s].resize(nb);
  }
  std::vector<Anchor> first_anchors;
  for (int b = 0; b < nb; ++b) {
    rk_q0_[b] = bodies_[b].q;
    rk_v0_[b] = bodies_[b].v;
  }
  for (int s = 0; s < 4; ++s) {
    for (int b = 0; b < nb; ++b) {
      if (s > 0) {
        bodies_[b].q = rk_q0_[b] + (kStage[s] * h) * rk_kq_[s - 1][b];
        core::normalize(*bodies_[b].model, bodies_[b].q);
        bodies_[b].v = rk_v0_[b] + (kStage[s] * h) * rk_kv_[s - 1][b];
      }
      work_[b].mass_matrix_ready = false;
    }
    points_.clear();
    pairs_.clear();
    point_forces_.clear();
    next_anchors_.clear();
    StageClock clock(counters_.timers);
    if (scene_.contacts()) {
      run_kinematics();
      clock.lap(TimedPart::kKinematics);
      run_collision_search();  // times its two searches itself
      clock.skip();
      if (!points_.empty()) {
        run_contact_forces();
        for (ContactPair& p : pairs_) p.wrench = p.wrench0;
        clock.lap(TimedPart::kContactForces);
      }
    }
    run_forward_dynamics();
    clock.lap(TimedPart::kDynamics);
    if (s == 0) first_anchors = next_anchors_;
    for (int b = 0; b < nb; ++b) {
      core::configuration_rate(*bodies_[b].model, bodies_[b].q, bodies_[b].v, rk_kq_[s][b]);
      rk_kv_[s][b] = work_[b].acceleration;
    }
  }
  StageClock clock(counters_.timers);
  counters_.count(Stage::kIntegration);
  for (int b = 0; b < nb; ++b) {
    Body& body = bodies_[b];
    body.q = rk_q0_[b] +
             (h / 6.0) * (rk_kq_[0][b] + 2.0 * rk_kq_[1][b] + 2.0 * rk_kq_[2][b] + rk_kq_[3][b]);
    core::normalize(*body.model, body.q);
    body.v = rk_v0_[b] +
             (h / 6.0) * (rk_kv_[0][b] + 2.0 * rk_kv_[1][b] + 2.0 * rk_kv_[2][b] + rk_kv_[3][b]);
  }
  clock.lap(TimedPart::kIntegration);
  if (scene_.hard_limits) {
    // after an RK4 step limits act as a kinematic stop: position clamped, outward speed removed
    counters_.count(Stage::kLimitProjection);
    for (int b = 0; b < nb; ++b) {
      const core::Model& m = *bodies_[b].model;
      for (int i = 1; i < m.njoints; ++i) {
        if (m.joint_type[i] != core::JointType::kRevolute &&
            m.joint_type[i] != core::JointType::kPrismatic) {
          continue;
        }
        double& q = bodies_[b].q[m.idx_q[i]];
        double& v = bodies_[b].v[m.idx_v[i]];
        if (q > m.limits[i].upper) {
          q = m.limits[i].upper;
          v = std::min(v, 0.0);
        } else if (q < m.limits[i].lower) {
          q = m.limits[i].lower;
          v = std::max(v, 0.0);
        }
      }
    }
    clock.lap(TimedPart::kLimits);
  }
  next_anchors_ = std::move(first_anchors);
  keep_anchors();
}

void World::run_kinematics() {
  counters_.count(Stage::kKinematics);
  for (int b = 0; b < body_count(); ++b) {
    core::forward_kinematics(*work_[b].dynamics, work_[b].data, bodies_[b].q, bodies_[b].v);
  }
}

void World::run_collision_search() {
  counters_.count(Stage::kCollisionSearch);
  StageClock clock(counters_.timers);
  for (int b = 0; b < body_count(); ++b) {
    Work& w = work_[b];
    if (scene_.ground_contact) {
      find_environment_contacts(b, w.shapes, w.data, environment_, points_);
      clock.lap(TimedPart::kGroundSearch);
    }
    if (scene_.self_collision) {
      find_self_contacts(b, w.shapes, w.data, w.sweep_order, points_);
      clock.lap(TimedPart::kSelfSearch);
    }
  }
  group_into_pairs(points_, pairs_);
}

void World::run_integration() {
  counters_.count(Stage::kIntegration);
  const double h = settings_.step;
  for (int b = 0; b < body_count(); ++b) {
    Body& body = bodies_[b];
    body.v = v_next_[b];
    core::integrate(*body.model, body.q, body.v, h, body.q);
  }
  // joints stopped by an impact this step rest on their limits
  if (scene_.hard_limits) {
    for (const LimitSnap& s : limit_snaps_) bodies_[s.body].q[s.q_index] = s.value;
  }
}

void World::keep_anchors() { anchors_.swap(next_anchors_); }

}  // namespace sim
