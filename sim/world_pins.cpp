// The dynamic_pins stage of sim::World: bodies whose drag, pins and joint references act at
// acceleration level (ik/acceleration_solver.hpp, Yamane ch. 9). Their joints move as the tasks
// ask; their root moves as gravity and the contact forces of the step's start make it (explicit,
// as in the book); the torques that do it come out of inverse dynamics.
#include <algorithm>

#include "core/crba.hpp"
#include "core/jacobian.hpp"
#include "core/rnea.hpp"
#include "sim/world.hpp"

namespace sim {

World::Work::Work(const Work& o)
    : dynamics(o.dynamics),
      data(o.data),
      shapes(o.shapes),
      sweep_order(o.sweep_order),
      acceleration(o.acceleration),
      bias(o.bias),
      generalized(o.generalized),
      scratch(o.scratch),
      f_ext(o.f_ext),
      handles(o.handles),
      handle_pair(o.handle_pair),
      handle_sign(o.handle_sign),
      handle_jdot_v(o.handle_jdot_v),
      osim(o.osim),
      Phi(o.Phi),
      mass_matrix_ready(o.mass_matrix_ready),
      pins(o.pins),
      // a copy gets a workspace of its own, so two worlds never share scratch space
      pin_solver(o.pin_solver ? std::make_shared<ik::AccelerationSolver>(*o.pin_solver) : nullptr),
      contact_force(o.contact_force),
      handle_jacobian(o.handle_jacobian),
      pinned(o.pinned),
      fall(o.fall),
      falling(o.falling),
      balance(o.balance),
      balanced_pins(o.balanced_pins) {}

World::Work& World::Work::operator=(const Work& o) {
  if (this != &o) *this = Work(o);
  return *this;
}

void World::set_pin_problem(int i, const ik::Problem& problem) {
  const Body& b = bodies_.at(i);
  if (b.model->njoints < 2 || b.model->joint_type[1] != core::JointType::kFree) {
    throw SimError("body '" + b.name + "': dynamics-backed pins need a free root joint");
  }
  Work& w = work_[i];
  w.pins = problem;
  if (!w.pin_solver) {
    w.pin_solver = std::make_shared<ik::AccelerationSolver>(*b.model, pin_settings_);
    w.contact_force = Eigen::VectorXd::Zero(b.model->nv);
    w.handle_jacobian = core::FrameJacobian(b.model->nv);
    w.fall = FallResponse(*b.model, environment_.ground);
  }
}

void World::clear_pin_problem(int i) { work_.at(i).pins.reset(); }

ik::Problem* World::pin_problem(int i) {
  Work& w = work_.at(i);
  return w.pins ? &*w.pins : nullptr;
}

void World::set_pin_settings(const ik::AccelerationSettings& settings) {
  const std::string error = ik::validate(settings);
  if (!error.empty()) throw SimError("pins." + error);
  pin_settings_ = settings;
  for (Work& w : work_) {
    if (w.pin_solver) w.pin_solver->set_settings(settings);
  }
}

void World::set_balance_settings(const BalanceSettings& settings) {
  const std::string error = validate(settings);
  if (!error.empty()) throw SimError(error);
  balance_settings_ = settings;
}

const ik::AccelerationSolver* World::pin_solver(int i) const {
  return work_.at(i).pin_solver.get();
}

void World::set_fall_settings(const FallSettings& settings) {
  const std::string error = validate(settings);
  if (!error.empty()) throw SimError(error);
  fall_settings_ = settings;
}

const Eigen::VectorXd* World::driving_forces(int i) const {
  const Work& w = work_.at(i);
  if (w.falling) return &w.fall.joint_forces();
  if (w.pinned) return &w.pin_solver->torque();
  return nullptr;
}

bool World::on_ground(int b) const {
  return std::any_of(pairs_.begin(), pairs_.end(), [&](const ContactPair& p) {
    return p.partner_body == -1 && p.body == b &&
           p.wrench.tail<3>().dot(environment_.ground.normal) > 0;
  });
}

bool World::has_pins(int b) const { return scene_.dynamic_pins && work_[b].pins.has_value(); }

bool World::dynamically_pinned(int b) const { return has_pins(b) && !work_[b].fall.fallen(); }

bool World::let_go(int b) const { return has_pins(b) && work_[b].fall.fallen(); }

void World::prepare_fallen() {
  const double h = settings_.step;
  for (int b = 0; b < body_count(); ++b) {
    if (!let_go(b)) continue;
    counters_.count(Stage::kBiasForces);
    counters_.count(Stage::kMassMatrix);
    Work& w = work_[b];
    const Body& body = bodies_[b];
    const core::Model& m = *w.dynamics;
    core::compute_joint_jacobians(m, w.data);
    w.bias = core::bias_forces(m, w.data, body.q, body.v);
    core::crba(m, w.data, body.q);
    w.fall.prepare(m, w.data, body.q, body.v, body.tau, *w.pins, fall_settings_, h);
    // the tone at the step's end, (H + diag(h D + h² K)) a = drive − b + Q, factorized for the
    // implicit contact solve and the forward dynamics alike
    w.data.LTDL = w.data.M;
    w.data.LTDL.diagonal() += w.fall.diagonal();
    core::ltdl_factorize(m, w.data.LTDL);
    w.mass_matrix_ready = true;
    w.falling = true;
  }
}

const Eigen::VectorXd& World::joint_forces_of(int b) const {
  return work_[b].falling ? work_[b].fall.drive() : bodies_[b].tau;
}

// Q = Σ ±J_kᵀ τ_k over the pairs that touch body b, each wrench at its reference point
void World::contact_joint_forces(int b) {
  Work& w = work_[b];
  w.contact_force.setZero();
  for (const ContactPair& p : pairs_) {
    for (const auto& [link, sign] : {std::pair{p.body == b ? p.link : -1, 1.0},
                                     {p.partner_body == b ? p.partner_link : -1, -1.0}}) {
      if (link < 0) continue;
      core::point_jacobian(*w.dynamics, w.data, link, w.data.X_W[link].inverse_apply(p.ref_W),
                           w.handle_jacobian);
      w.contact_force.noalias() +=
          sign * w.handle_jacobian.angular.transpose() * p.wrench.head<3>();
      w.contact_force.noalias() += sign * w.handle_jacobian.linear.transpose() * p.wrench.tail<3>();
    }
  }
}

void World::run_dynamic_pins() {
  counters_.count(Stage::kBiasForces);
  counters_.count(Stage::kMassMatrix);
  counters_.count(Stage::kOperationalSpace);
  counters_.count(Stage::kForwardDynamics);
  const double h = settings_.step;
  for (int b = 0; b < body_count(); ++b) {
    if (!dynamically_pinned(b)) continue;
    Work& w = work_[b];
    const Body& body = bodies_[b];
    const core::Model& m = *w.dynamics;
    // kinematics ran this step: poses, velocities and J̇v in w.data; the joint axes next
    core::compute_joint_jacobians(m, w.data);
    contact_joint_forces(b);
    w.bias = core::bias_forces(m, w.data, body.q, body.v);
    core::crba(m, w.data, body.q);
    // from the next step on a fallen figure lets go (prepare_fallen)
    w.fall.update(m, w.data, environment_.ground, on_ground(b), fall_settings_);
    w.balance.update(*this, b, m, w.data, body.v, balance_settings_, *w.pins, w.balanced_pins);
    const ik::AccelerationReport& r =
        w.pin_solver->solve(w.balanced_pins, w.data, body.q, body.v, w.bias, w.contact_force);
    if (r.status != ik::AccelerationReport::Status::kOk) continue;  // passive this step
    w.acceleration = w.pin_solver->acceleration();
    v_next_[b] = body.v + h * w.acceleration;
    w.pinned = true;
  }
}

}  // namespace sim
