#include "cli/solve_request.hpp"

#include <algorithm>
#include <cmath>

#include "animator/document_json.hpp"
#include "cli/json_fields.hpp"
#include "cli/simulate_scene.hpp"
#include "cli/solve_physics.hpp"
#include "cli/solve_spec.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"
#include "ik/pin_hold.hpp"
#include "ik/solver.hpp"
#include "io/bundled_characters.hpp"
#include "sim/placement.hpp"

namespace cli {

namespace {

using core::Quaternion;
using core::Vector3;
using io::JsonField;
using io::JsonFields;
using nlohmann::json;

// Unknown fields are refused, not ignored: a misspelt or unsupported field (say "physic_dt")
// would otherwise change nothing and go unnoticed.
const std::initializer_list<std::string_view> kRequestKeys = {
    "character", "frames",           "dt",    "settings", "drag",      "drags",
    "pins",      "joint_references", "start", "effects",  "physics_dt"};

int link_by_name(JsonFields& f, const JsonField& field, const core::Model& m) {
  const std::string name = f.string(field);
  const int i = m.link_index(name);
  if (i < 1)
    f.fail(field, "unknown link " + io::in_quotes(name) + " in character '" + m.name + "'");
  return i;
}

ik::TaskMode mode_from(JsonFields& f, const JsonField& mode, ik::TaskMode fallback) {
  if (!mode) return fallback;
  const std::string s = f.string(mode);
  const auto m = ik::task_mode_from_string(s);
  if (!m) f.fail(mode, io::in_quotes(s) + " is not one of position, orientation, pose");
  return *m;
}

// The request's "dt" and its "settings" object (the session file's reader, animator/document_json);
// the frame time is the request's own, so "settings.dt" is refused.
ik::SolverSettings solver_settings_from(JsonFields& f, const JsonField& r) {
  ik::SolverSettings s;
  s.dt = f.number_or(r["dt"], s.dt);
  const JsonField j = r["settings"];
  if (!j) return s;
  animator::read_settings(f, j, s);
  if (const JsonField dt = j["dt"]) f.fail(dt, "unknown key (the frame time is the request's dt)");
  if (const std::string e = ik::validate(s); !e.empty()) f.fail(j, e);
  return s;
}

DragSpec drag_from(JsonFields& f, const JsonField& j, const core::Model& m) {
  f.object(j);
  f.refuse_unknown_keys(
      j, {"link", "target", "rotation", "point", "mode", "release_at", "gain", "weight"});
  DragSpec d;
  d.task.link = link_by_name(f, j["link"], m);
  if (!j["target"] && !j["rotation"]) {
    f.fail(j, "needs a target [x, y, z] and/or a rotation [w, x, y, z]");
  }
  if (j["point"]) d.task.p_LinkPoint = f.vector3(j["point"]);
  if (j["target"]) d.task.target_W = f.vector3(j["target"]);
  ik::TaskMode fallback = ik::TaskMode::kPosition;
  if (j["rotation"]) {
    d.task.target_R_W = f.quaternion(j["rotation"]);
    fallback = j["target"] ? ik::TaskMode::kPose : ik::TaskMode::kOrientation;
  }
  d.task.mode = mode_from(f, j["mode"], fallback);
  d.task.gain = f.number_or(j["gain"], ik::kDefaultGain);
  d.task.weight = f.number_or(j["weight"], 1.0);
  d.release_at = static_cast<int>(f.integer_or(j["release_at"], -1, 0, 1000000));
  return d;
}

// A pin's target and rotation default to where the pinned point is in `data` (frame 0).
ik::LinkTask pin_from(JsonFields& f,
                      const JsonField& p,
                      const core::Model& m,
                      const core::Data& data) {
  f.object(p);
  f.refuse_unknown_keys(p, {"link", "mode", "target", "rotation", "point", "gain", "weight"});
  ik::LinkTask pin{.role = ik::kPin};
  pin.link = link_by_name(f, p["link"], m);
  pin.mode = mode_from(f, p["mode"], ik::TaskMode::kPosition);
  if (p["point"]) pin.p_LinkPoint = f.vector3(p["point"]);
  pin.target_W =
      p["target"] ? f.vector3(p["target"]) : Vector3(data.X_W[pin.link] * pin.p_LinkPoint);
  pin.target_R_W = p["rotation"] ? f.quaternion(p["rotation"]) : Quaternion(data.X_W[pin.link].R);
  pin.gain = f.number_or(p["gain"], ik::kDefaultGain);
  pin.weight = f.number_or(p["weight"], 1.0);
  return pin;
}

// {"joint": angle} for 1-DOF joints, {"joint": [w, x, y, z]} for spherical ones, or either as
// {"value": ..., "gain": ..., "weight": ...}
ik::JointReferenceTask reference_from(JsonFields& f,
                                      const JsonField& ref,
                                      const std::string& name,
                                      const core::Model& m) {
  const int j = m.joint_index(name);
  if (j < 1) f.fail(ref, "unknown joint " + io::in_quotes(name));
  ik::JointReferenceTask t;
  t.joint = j;
  JsonField v = ref;
  if (ref->is_object()) {
    f.refuse_unknown_keys(ref, {"value", "gain", "weight"});
    v = f.present(ref["value"]);
    t.gain = f.number_or(ref["gain"], ik::kDefaultGain);
    t.weight = f.number_or(ref["weight"], t.weight);
  }
  switch (m.joint_type[j]) {
    case core::JointType::kRevolute:
    case core::JointType::kPrismatic:
      t.q_ref = f.number(v);
      break;
    case core::JointType::kSpherical:
      t.R_ref = f.quaternion(v);
      break;
    default:
      f.fail(ref, "joint " + io::in_quotes(name) + " is " + core::to_string(m.joint_type[j]) +
                      "; references apply to 1-DOF and spherical joints");
  }
  return t;
}

// The configuration at frame 0: "start.q", or the rest configuration.
Eigen::VectorXd start_from(JsonFields& f, const JsonField& start, const core::Model& m) {
  if (!start) return core::rest_configuration(m);
  f.object(start);
  f.refuse_unknown_keys(start, {"q"});
  Eigen::VectorXd q = f.numbers(start["q"], m.nq);
  if (const std::string e = core::check_configuration(m, q, 1e-3); !e.empty()) {
    f.fail(start["q"], e);
  }
  core::normalize(m, q);
  return q;
}

// "effects" (names of sim::Effect) and "physics_dt". With ground_contact the character starts
// standing on the ground (sim::standing_configuration), so that pins default to where the points
// are there. A field that would change nothing on the chosen path is refused.
void read_physics(JsonFields& f, const JsonField& r, SolveSpec& out) {
  out.scene = read_effects(f, r["effects"]);
  if (!out.physics()) {
    if (r["physics_dt"]) f.fail(r["physics_dt"], "applies only with effects");
    return;
  }
  out.physics_dt = f.number_or(r["physics_dt"], out.physics_dt, {1e-6, 0.1});
  if (r["settings"]) {
    f.fail(r["settings"], "applies to the kinematic solver only (without effects)");
  }
  const core::Model& m = *out.model;
  if ((out.scene.ground_contact || out.scene.dynamic_pins) &&
      m.joint_type[1] != core::JointType::kFree) {
    f.fail(r["effects"], "ground_contact and dynamic_pins need a free root joint; character '" +
                             m.name + "' has a " + core::to_string(m.joint_type[1]) + " root");
  }
  if (out.scene.ground_contact) out.q = sim::standing_configuration(m, out.q, {});
}

// With effects, drags, pins and references act only through dynamic_pins.
void refuse_idle_tasks(JsonFields& f, const JsonField& r, const SolveSpec& s) {
  if (!s.physics() || s.scene.dynamic_pins) return;
  for (const char* key : {"drag", "drags", "pins", "joint_references"}) {
    if (r[key])
      f.fail(r[key], "acts on a simulated body only with 'dynamic_pins' among the effects");
  }
}

SolveSpec read_request(JsonFields& f, const JsonField& r) {
  f.object(r);
  f.refuse_unknown_keys(r, kRequestKeys);
  const JsonField character = r["character"];
  if (!character) f.fail(character, "missing (a bundled name or a file)");
  SolveSpec out;
  try {
    out.model = io::load_character(f.string(character)).model;
  } catch (const core::ModelError& e) {
    f.fail(character, e.what());
  }
  const core::Model& m = *out.model;
  out.frames = static_cast<int>(f.integer_or(r["frames"], 120, 0, 1000000));
  out.settings = solver_settings_from(f, r);
  out.q = start_from(f, r["start"], m);
  read_physics(f, r, out);
  core::Data data(m);
  core::forward_kinematics(m, data, out.q);
  if (r["drag"]) out.drags.push_back(drag_from(f, r["drag"], m));
  if (const JsonField drags = r["drags"]) {
    for (std::size_t k = 0; k < f.array(drags).size(); ++k) {
      out.drags.push_back(drag_from(f, drags[k], m));
    }
  }
  if (const JsonField pins = r["pins"]) {
    for (std::size_t k = 0; k < f.array(pins).size(); ++k) {
      out.pins.push_back(pin_from(f, pins[k], m, data));
    }
  }
  if (const JsonField refs = r["joint_references"]) {
    if (!refs->is_object()) f.fail(refs, "expected an object keyed by joint name");
    for (const auto& [name, value] : refs->items()) {
      out.references.push_back(reference_from(f, refs[name], name, m));
    }
  }
  refuse_idle_tasks(f, r, out);
  return out;
}

// the errors of one frame, as the output lists them
json frame_errors(const std::vector<DragSpec>& drags,
                  const core::Data& data,
                  const ik::Report& rep) {
  double drag_error = 0, pin_p = 0, pin_r = 0;
  for (const DragSpec& d : drags) {
    const ik::TaskError e = ik::link_task_error(data, d.task);
    drag_error = std::max(drag_error,
                          d.task.mode == ik::TaskMode::kOrientation ? e.orientation : e.position);
  }
  for (const ik::TaskReport& t : rep.tasks) {
    if (std::string(t.kind) != "pin") continue;
    pin_p = std::max(pin_p, t.position_error);
    pin_r = std::max(pin_r, t.orientation_error);
  }
  json frame;
  frame["drag_error"] = drag_error;
  frame["pin_position_error"] = pin_p;
  frame["pin_orientation_error"] = pin_r;
  frame["joint_speed"] = rep.max_joint_speed;
  frame["limit_violation"] = rep.limit_violation;
  frame["top_rank"] = rep.top_rank;
  frame["microseconds"] = rep.microseconds;
  return frame;
}

// the kinematic path: the IK solver steps `q` once per frame
json run_kinematic(const SolveSpec& r, Eigen::VectorXd& q) {
  const core::Model& m = *r.model;
  core::Data data(m);
  core::forward_kinematics(m, data, q);

  ik::Problem problem;
  for (const ik::LinkTask& pin : r.pins) problem.add(pin, ik::pin_priority(r.settings));
  for (const ik::JointReferenceTask& t : r.references) problem.add(t);
  std::vector<int> drag_ids;
  for (const DragSpec& d : r.drags) drag_ids.push_back(ik::add_drag(d.task, r.settings, problem));

  ik::Solver solver(m, r.settings);
  ik::PinHold pin_hold(m);  // hard pins: projected back after every step (docs/ik.md)
  json out_frames = json::array();
  for (int frame = 0; frame < r.frames; ++frame) {
    for (std::size_t k = 0; k < r.drags.size(); ++k) {
      if (r.drags[k].release_at == frame) problem.remove(drag_ids[k]);
    }
    const ik::Report& rep = solver.step(problem, data, q);
    if (rep.status != ik::Report::Status::kOk) {
      throw RequestError("solver rejected the problem: " + rep.message);
    }
    const int corrections = pin_hold.hold(r.settings, problem, data, q).corrections;
    if (corrections > 0) solver.refresh_report(problem, data, q);
    json errors = frame_errors(r.drags, data, rep);
    errors["pin_corrections"] = corrections;
    out_frames.push_back(std::move(errors));
  }
  return out_frames;
}

}  // namespace

json run_solve_request(const json& request) {
  JsonFields f = request_fields();
  SolveSpec r = io::rethrow_as<RequestError>([&] { return read_request(f, JsonField(request)); });
  const core::Model& m = *r.model;
  Eigen::VectorXd& q = r.q;
  json out_frames = r.physics() ? run_physics(r, q) : run_kinematic(r, q);
  core::Data data(m);
  core::forward_kinematics(m, data, q);
  json links = json::array();
  for (int i = 1; i < m.njoints; ++i) {
    const Vector3& p = data.X_W[i].p;
    links.push_back({{"name", m.link_name[i]}, {"p", {p.x(), p.y(), p.z()}}});
  }
  json out;
  out["character"] = m.name;
  out["frames"] = out_frames;
  out["final"] = {{"q", std::vector<double>(q.data(), q.data() + q.size())}, {"links", links}};
  return out;
}

}  // namespace cli
