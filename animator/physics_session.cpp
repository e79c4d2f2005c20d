#include "animator/physics_session.hpp"

#include <algorithm>
#include <chrono>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "sim/balance.hpp"
#include "sim/placement.hpp"

namespace animator {

namespace {

sim::WorldSettings figure_settings(const core::Model& model) {
  sim::WorldSettings s;
  s.contact = sim::figure_contact_settings(model.total_mass());
  return s;
}

}  // namespace

bool simulates(const sim::Scene& scene) {
  return scene.gravity || scene.ground_contact || scene.hard_limits || scene.self_collision ||
         scene.dynamic_pins;
}

PhysicsSession::PhysicsSession(std::shared_ptr<const core::Model> model,
                               const sim::Scene& scene,
                               const Eigen::VectorXd& q)
    : model_(std::move(model)), world_(figure_settings(*model_)), data_(*model_) {
  const sim::GroundPlane& ground = world_.environment().ground;
  reference_ = scene.ground_contact ? sim::standing_configuration(*model_, q, ground) : q;
  world_.add_body(model_->name, model_, reference_);
  if (scene.ground_contact) {
    core::forward_kinematics(*model_, data_, reference_);
    for (const int link : sim::supporting_links(*model_, reference_, ground)) {
      supports_.push_back({link, core::Quaternion(data_.X_W[link].R)});
    }
  }
  world_.set_scene(scene);
  set_tasks({}, std::nullopt);
}

void PhysicsSession::set_scene(const sim::Scene& scene) { world_.set_scene(scene); }

void PhysicsSession::set_tasks(const std::vector<Pin>& pins,
                               const std::optional<ik::LinkTask>& drag) {
  // dynamics-backed pins need a free root; a figure without one is simulated passively
  if (model_->njoints < 2 || model_->joint_type[1] != core::JointType::kFree) return;
  // when a drag ends the joints keep the posture it made, as kinematic posing keeps the pose
  if (dragging_ && !drag) reference_ = world_.body(0).q;
  dragging_ = drag.has_value();
  problem_.clear();
  ik::add_joint_references(*model_, reference_, problem_);
  for (const Pin& p : pins) {
    problem_.add(p.task());
  }
  // the links it stands on get weak orientation pins (Yamane §9.4), unless the user pinned them:
  // the balance feedback (sim/balance_control.hpp) tilts them to keep the figure over its feet
  for (const auto& [link, R] : supports_) {
    if (std::any_of(pins.begin(), pins.end(), [l = link](const Pin& p) { return p.link == l; })) {
      continue;
    }
    problem_.add(ik::LinkTask{
        .role = ik::kPin, .link = link, .target_R_W = R, .mode = ik::TaskMode::kOrientation});
  }
  if (drag) problem_.add(*drag);
  world_.set_pin_problem(0, problem_);
}

void PhysicsSession::advance(double dt) {
  world_.reset_counters();
  world_.advance(dt);
  frame_timers_ = world_.counters().timers;
}

PhysicsMeasures PhysicsSession::measures() const {
  core::forward_kinematics(*model_, data_, world_.body(0).q);
  const sim::BalanceMeasures b = sim::measure_balance(world_, 0, *model_, data_);
  PhysicsMeasures out;
  out.com = b.com;
  out.cop = b.cop;
  out.support_polygon = b.polygon;
  out.balanced = b.com_supported;
  out.fallen = world_.fallen(0);
  for (const sim::ContactPair& p : world_.contact_pairs()) {
    if (p.body != 0 || p.partner_body != -1) continue;  // self contact, or another body's
    out.contacts.push_back({p.ref_W, p.wrench.tail<3>()});
  }
  for (int e = 0; e < sim::kEffectCount; ++e) {
    out.effect_us[e] = 1e6 * sim::effect_seconds(frame_timers_, sim::kAllEffects[e]);
  }
  for (const auto t : frame_timers_.time) {
    out.total_us += std::chrono::duration<double, std::micro>(t).count();
  }
  return out;
}

}  // namespace animator
