#include "sim/world.hpp"

#include <cmath>

#include "core/centroidal.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace sim {

World::World(const WorldSettings& settings, const Environment& environment) {
  set_settings(settings);
  set_environment(environment);
}

int World::add_body(const std::string& name,
                    std::shared_ptr<const core::Model> model,
                    const Eigen::VectorXd& q,
                    const Eigen::VectorXd& v) {
  const std::string who = "body '" + name + "'";
  if (!model) throw SimError(who + ": no model");
  if (name.empty()) throw SimError("body: a name is required");
  if (body_index(name) >= 0) throw SimError(who + ": a body of that name exists already");
  const std::string q_error = core::check_configuration(*model, q);
  if (!q_error.empty()) throw SimError(who + ".q: " + q_error);
  if (v.size() != 0 && (v.size() != model->nv || !v.allFinite())) {
    throw SimError(who + ".v: must hold " + std::to_string(model->nv) + " finite numbers");
  }
  Body b;
  b.name = name;
  b.model = model;
  b.q = q;
  b.v = v.size() ? v : Eigen::VectorXd::Zero(model->nv);
  b.tau = Eigen::VectorXd::Zero(model->nv);
  bodies_.push_back(std::move(b));
  Work w(*model);
  w.shapes = build_body_shapes(*model, core::rest_configuration(*model));
  w.acceleration = Eigen::VectorXd::Zero(model->nv);
  w.bias = Eigen::VectorXd::Zero(model->nv);
  w.generalized = Eigen::VectorXd::Zero(model->nv);
  w.scratch = Eigen::VectorXd::Zero(model->nv);
  w.f_ext.assign(model->njoints, core::Force::Zero());
  work_.push_back(std::move(w));
  v_next_.push_back(Eigen::VectorXd::Zero(model->nv));
  rebuild_dynamics_models();
  return body_count() - 1;
}

int World::body_index(const std::string& name) const {
  for (int i = 0; i < body_count(); ++i) {
    if (bodies_[i].name == name) return i;
  }
  return -1;
}

void World::set_state(int i, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  Body& b = bodies_.at(i);
  const std::string q_error = core::check_configuration(*b.model, q);
  if (!q_error.empty()) throw SimError("body '" + b.name + "'.q: " + q_error);
  if (v.size() != b.model->nv || !v.allFinite()) {
    throw SimError("body '" + b.name + "'.v: must hold " + std::to_string(b.model->nv) +
                   " finite numbers");
  }
  b.q = q;
  b.v = v;
  work_.at(i).fall.reset();  // a figure set on its feet stands again
  anchors_.clear();          // a teleported body starts its contacts afresh
}

void World::set_joint_forces(int i, const Eigen::VectorXd& tau) {
  Body& b = bodies_.at(i);
  if (tau.size() != b.model->nv || !tau.allFinite()) {
    throw SimError("body '" + b.name + "'.tau: must hold " + std::to_string(b.model->nv) +
                   " finite numbers");
  }
  b.tau = tau;
}

void World::set_scene(const Scene& scene) {
  const bool gravity_changed = scene.gravity != scene_.gravity;
  scene_ = scene;
  if (gravity_changed) rebuild_dynamics_models();
  if (!scene_.contacts()) anchors_.clear();
}

void World::set_settings(const WorldSettings& settings) {
  const std::string error = validate(settings);
  if (!error.empty()) throw SimError(error);
  settings_ = settings;
}

void World::set_environment(const Environment& environment) {
  const std::string error = validate(environment);
  if (!error.empty()) throw SimError(error);
  environment_ = environment;
  anchors_.clear();
}

bool World::simulates() const {
  return scene_.gravity || scene_.ground_contact || scene_.hard_limits || scene_.self_collision ||
         scene_.dynamic_pins;
}

void World::rebuild_dynamics_models() {
  for (int i = 0; i < body_count(); ++i) {
    if (scene_.gravity) {
      work_[i].dynamics = bodies_[i].model;
    } else {
      auto weightless = std::make_shared<core::Model>(*bodies_[i].model);
      weightless->gravity.setZero();
      work_[i].dynamics = std::move(weightless);
    }
  }
}

int World::advance(double dt) {
  if (!std::isfinite(dt) || dt < 0) throw SimError("dt: must be a finite number >= 0");
  const double h = settings_.step;
  remainder_ += dt;
  // a remainder within a billionth of a step of h counts as a whole step (rounding of the sum)
  const auto n = static_cast<long long>(std::floor(remainder_ / h + 1e-9));
  for (long long k = 0; k < n; ++k) step();
  remainder_ = std::max(0.0, remainder_ - static_cast<double>(n) * h);
  return static_cast<int>(n);
}

void World::step() {
  if (simulates()) {
    if (settings_.integrator == Integrator::kRk4) {
      step_rk4();
    } else {
      step_euler();
    }
  }
  time_ += settings_.step;
  ++steps_;
}

double World::kinetic_energy(int i) const {
  const Body& b = bodies_.at(i);
  core::Data data(*b.model);
  core::forward_kinematics(*b.model, data, b.q, b.v);
  return core::kinetic_energy(*b.model, data);
}

double World::potential_energy(int i) const {
  if (!scene_.gravity) return 0;
  const Body& b = bodies_.at(i);
  core::Data data(*b.model);
  core::forward_kinematics(*b.model, data, b.q);
  return core::potential_energy(*b.model, data);
}

double World::energy() const {
  double e = 0;
  for (int i = 0; i < body_count(); ++i) e += kinetic_energy(i) + potential_energy(i);
  return e;
}

}  // namespace sim
