#include "cli/solve_physics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "cli/json_fields.hpp"
#include "core/kinematics.hpp"
#include "sim/balance.hpp"
#include "sim/world.hpp"

namespace cli {

namespace {

using core::Vector3;
using nlohmann::json;

json point(const Vector3& p) { return {p.x(), p.y(), p.z()}; }

json point_or_null(const std::optional<Vector3>& p) { return p ? point(*p) : json(nullptr); }

json points(const std::vector<Vector3>& polygon) {
  json out = json::array();
  for (const Vector3& v : polygon) out.push_back(point(v));
  return out;
}

// drag and pin errors from the body's kinematics, as the kinematic path reports them
void add_task_errors(const SolveSpec& s, const core::Data& data, json& frame) {
  double drag_error = 0, pin_p = 0, pin_r = 0;
  for (const DragSpec& d : s.drags) {
    const ik::TaskError e = ik::link_task_error(data, d.task);
    drag_error = std::max(drag_error,
                          d.task.mode == ik::TaskMode::kOrientation ? e.orientation : e.position);
  }
  for (const ik::LinkTask& pin : s.pins) {
    const ik::TaskError e = ik::link_task_error(data, pin);
    if (pin.mode != ik::TaskMode::kOrientation) pin_p = std::max(pin_p, e.position);
    if (pin.mode != ik::TaskMode::kPosition) pin_r = std::max(pin_r, e.orientation);
  }
  frame["drag_error"] = drag_error;
  frame["pin_position_error"] = pin_p;
  frame["pin_orientation_error"] = pin_r;
}

json measure_frame(const SolveSpec& s, const sim::World& world, core::Data& data) {
  const core::Model& m = *s.model;
  core::forward_kinematics(m, data, world.body(0).q);
  const sim::BalanceMeasures b = sim::measure_balance(world, 0, m, data);
  const ik::AccelerationSolver* pins = world.pin_solver(0);
  json frame;
  frame["com"] = point(b.com);
  frame["cop"] = point_or_null(b.cop);
  frame["support_polygon"] = points(b.polygon);
  frame["contact_force"] = b.normal_force;
  // fallen, forward dynamics moves the figure: its root rows hold by construction
  const bool driven = s.scene.dynamic_pins && pins && !world.fallen(0);
  frame["base_residual"] = driven ? pins->report().root_residual : 0.0;
  frame["pelvis"] = point(data.X_W[1].p);
  frame["fallen"] = world.fallen(0);
  add_task_errors(s, data, frame);
  return frame;
}

// the drags, pins and references as one problem; drag_ids: the drags' task ids
ik::Problem pin_problem(const SolveSpec& s, std::vector<int>& drag_ids) {
  ik::Problem problem;
  for (const ik::LinkTask& pin : s.pins) problem.add(pin);
  for (const ik::JointReferenceTask& t : s.references) problem.add(t);
  for (const DragSpec& d : s.drags) drag_ids.push_back(problem.add(d.task));
  return problem;
}

}  // namespace

json run_physics(const SolveSpec& s, Eigen::VectorXd& q) {
  const core::Model& m = *s.model;
  sim::WorldSettings settings;
  settings.step = s.physics_dt;
  settings.contact = sim::figure_contact_settings(m.total_mass());
  sim::World world(settings);
  std::vector<int> drag_ids;
  try {
    world.add_body(m.name, s.model, s.q);
    world.set_scene(s.scene);
    if (s.scene.dynamic_pins) world.set_pin_problem(0, pin_problem(s, drag_ids));
  } catch (const sim::SimError& e) {
    throw RequestError(std::string("/effects: ") + e.what());
  }
  core::Data data(m);
  json frames = json::array();
  for (int frame = 0; frame < s.frames; ++frame) {
    for (std::size_t k = 0; k < drag_ids.size(); ++k) {
      if (s.drags[k].release_at == frame) world.pin_problem(0)->remove(drag_ids[k]);
    }
    const auto t0 = std::chrono::steady_clock::now();
    world.advance(s.settings.dt);
    const auto t1 = std::chrono::steady_clock::now();
    json out = measure_frame(s, world, data);
    out["microseconds"] = std::chrono::duration<double, std::micro>(t1 - t0).count();
    frames.push_back(std::move(out));
  }
  q = world.body(0).q;
  return frames;
}

}  // namespace cli
