#include "cli/solve_request.hpp"

#include <algorithm>
#include <cmath>

#include "cli/json_fields.hpp"
#include "core/configuration.hpp"
#include "io/bundled_characters.hpp"
#include "core/kinematics.hpp"
#include "ik/solver.hpp"

namespace cli {

namespace {

using core::Quaternion;
using core::Vector3;
using nlohmann::json;

int link_by_name(const core::Model& m, const json& j, const std::string& field) {
  const std::string name = string(j, field);
  const int i = m.link_index(name);
  if (i < 1) throw RequestError(field + ": unknown link '" + name + "' in character '" + m.name + "'");
  return i;
}

ik::TaskMode mode_from(const json& parent, const std::string& field, ik::TaskMode fallback) {
  if (!parent.contains("mode")) return fallback;
  const std::string s = string(parent["mode"], field + "/mode");
  if (s == "position") return ik::TaskMode::kPosition;
  if (s == "orientation") return ik::TaskMode::kOrientation;
  if (s == "pose") return ik::TaskMode::kPose;
  throw RequestError(field + "/mode: '" + s + "' is not one of position, orientation, pose");
}

ik::SolverSettings settings_from(const json& r) {
  ik::SolverSettings s;
  s.dt = number_or(r, "dt", "", s.dt);
  if (!r.contains("settings")) return s;
  const json& j = r["settings"];
  if (!j.is_object()) throw RequestError("/settings: expected an object");
  warn_unknown_keys(j, "/settings", {"damping", "iterations", "gains", "damping_schedule",
                                     "manipulability_threshold", "top_damping", "top_singular_value",
                                     "range_damping", "max_position_error", "max_orientation_error",
                                     "limit_margin", "max_joint_step", "joint_weights"});
  s.damping = number_or(j, "damping", "/settings", s.damping);
  if (j.contains("iterations")) s.iterations = integer_in(j["iterations"], "/settings/iterations", 1, 1000);
  if (j.contains("damping_schedule")) {
    const std::string d = string(j["damping_schedule"], "/settings/damping_schedule");
    const auto schedule = ik::damping_schedule_from_string(d);
    if (!schedule) throw RequestError("/settings/damping_schedule: '" + d + "' is not constant, manipulability or residual");
    s.damping_schedule = *schedule;
  }
  s.manipulability_threshold = number_or(j, "manipulability_threshold", "/settings", s.manipulability_threshold);
  s.top_damping = number_or(j, "top_damping", "/settings", s.top_damping);
  s.top_singular_value = number_or(j, "top_singular_value", "/settings", s.top_singular_value);
  s.range_damping = number_or(j, "range_damping", "/settings", s.range_damping);
  s.max_position_error = number_or(j, "max_position_error", "/settings", s.max_position_error);
  s.max_orientation_error = number_or(j, "max_orientation_error", "/settings", s.max_orientation_error);
  s.limit_margin = number_or(j, "limit_margin", "/settings", s.limit_margin);
  s.max_joint_step = number_or(j, "max_joint_step", "/settings", s.max_joint_step);
  if (j.contains("joint_weights")) {
    if (!j["joint_weights"].is_boolean()) throw RequestError("/settings/joint_weights: expected true or false");
    s.use_joint_weights = j["joint_weights"].get<bool>();
  }
  if (j.contains("gains")) {
    const json& g = j["gains"];
    if (!g.is_object()) throw RequestError("/settings/gains: expected an object");
    warn_unknown_keys(g, "/settings/gains", {"drag", "pin", "reference", "limit", "range"});
    s.drag_gain = number_or(g, "drag", "/settings/gains", s.drag_gain);
    s.pin_gain = number_or(g, "pin", "/settings/gains", s.pin_gain);
    s.reference_gain = number_or(g, "reference", "/settings/gains", s.reference_gain);
    s.limit_gain = number_or(g, "limit", "/settings/gains", s.limit_gain);
    s.range_gain = number_or(g, "range", "/settings/gains", s.range_gain);
  }
  if (const std::string e = ik::validate(s); !e.empty()) throw RequestError("/settings: " + e);
  return s;
}

struct DragSpec {
  ik::LinkTask task{.role = ik::kDrag};
  int release_at = -1;  // frame at which the drag is let go; -1: never
};

DragSpec drag_from(const core::Model& m, const json& j, const std::string& field) {
  if (!j.is_object()) throw RequestError(field + ": expected an object");
  warn_unknown_keys(j, field, {"link", "target", "rotation", "point", "mode", "release_at", "gain", "weight"});
  DragSpec d;
  if (!j.contains("link")) throw RequestError(field + "/link: missing");
  d.task.link = link_by_name(m, j["link"], field + "/link");
  if (!j.contains("target") && !j.contains("rotation")) {
    throw RequestError(field + ": needs a target [x, y, z] and/or a rotation [w, x, y, z]");
  }
  if (j.contains("point")) d.task.p_LinkPoint = vector3(j["point"], field + "/point");
  if (j.contains("target")) d.task.target_W = vector3(j["target"], field + "/target");
  ik::TaskMode fallback = ik::TaskMode::kPosition;
  if (j.contains("rotation")) {
    d.task.target_R_W = quaternion_wxyz(j["rotation"], field + "/rotation");
    fallback = j.contains("target") ? ik::TaskMode::kPose : ik::TaskMode::kOrientation;
  }
  d.task.mode = mode_from(j, field, fallback);
  d.task.gain = number_or(j, "gain", field, ik::kDefaultGain);
  d.task.weight = number_or(j, "weight", field, 1.0);
  if (j.contains("release_at")) d.release_at = integer_in(j["release_at"], field + "/release_at", 0, 1000000);
  return d;
}

}  // namespace

json run_solve_request(const json& r) {
  if (!r.is_object()) throw RequestError("/: expected an object");
  warn_unknown_keys(r, "", {"character", "frames", "dt", "settings", "drag", "drags", "pins",
                            "joint_references", "start"});
  if (!r.contains("character")) throw RequestError("/character: missing (a bundled name or a file)");
  io::LoadResult loaded;
  try {
    loaded = io::load_character(string(r["character"], "/character"));
  } catch (const core::ModelError& e) {
    throw RequestError(std::string("/character: ") + e.what());
  }
  const core::Model& m = *loaded.model;
  const int frames = r.contains("frames") ? integer_in(r["frames"], "/frames", 0, 1000000) : 120;
  ik::SolverSettings settings = settings_from(r);

  Eigen::VectorXd q = core::rest_configuration(m);
  if (r.contains("start")) {
    const json& s = r["start"];
    if (!s.is_object() || !s.contains("q") || !s["q"].is_array() || s["q"].size() != static_cast<size_t>(m.nq)) {
      throw RequestError("/start/q: expected an array of " + std::to_string(m.nq) + " numbers");
    }
    for (int k = 0; k < m.nq; ++k) q[k] = number(s["q"][k], "/start/q/" + std::to_string(k));
    if (const std::string e = core::check_configuration(m, q, 1e-3); !e.empty()) throw RequestError("/start/q: " + e);
    core::normalize(m, q);
  }
  core::Data data(m);
  core::forward_kinematics(m, data, q);

  // drags
  std::vector<DragSpec> drags;
  if (r.contains("drag")) drags.push_back(drag_from(m, r["drag"], "/drag"));
  if (r.contains("drags")) {
    if (!r["drags"].is_array()) throw RequestError("/drags: expected an array");
    for (size_t k = 0; k < r["drags"].size(); ++k) {
      drags.push_back(drag_from(m, r["drags"][k], "/drags/" + std::to_string(k)));
    }
  }
  // pins: default target is where the pinned point is at frame 0
  ik::Problem problem;
  std::vector<int> pin_ids;
  if (r.contains("pins")) {
    const json& pins = r["pins"];
    if (!pins.is_array()) throw RequestError("/pins: expected an array");
    for (size_t k = 0; k < pins.size(); ++k) {
      const std::string field = "/pins/" + std::to_string(k);
      const json& p = pins[k];
      if (!p.is_object()) throw RequestError(field + ": expected an object");
      warn_unknown_keys(p, field, {"link", "mode", "target", "rotation", "point", "gain", "weight"});
      if (!p.contains("link")) throw RequestError(field + "/link: missing");
      ik::LinkTask pin{.role = ik::kPin};
      pin.link = link_by_name(m, p["link"], field + "/link");
      pin.mode = mode_from(p, field, ik::TaskMode::kPosition);
      if (p.contains("point")) pin.p_LinkPoint = vector3(p["point"], field + "/point");
      pin.target_W = p.contains("target") ? vector3(p["target"], field + "/target")
                                          : Vector3(data.X_W[pin.link] * pin.p_LinkPoint);
      pin.target_R_W = p.contains("rotation") ? quaternion_wxyz(p["rotation"], field + "/rotation")
                                              : Quaternion(data.X_W[pin.link].R);
      pin.gain = number_or(p, "gain", field, ik::kDefaultGain);
      pin.weight = number_or(p, "weight", field, 1.0);
      pin_ids.push_back(problem.add(pin));
    }
  }
  // joint references: {"joint": angle} for 1-DOF joints, {"joint": [w, x, y, z]} for spherical
  if (r.contains("joint_references")) {
    const json& refs = r["joint_references"];
    if (!refs.is_object()) throw RequestError("/joint_references: expected an object keyed by joint name");
    for (const auto& [name, value] : refs.items()) {
      const std::string field = "/joint_references/" + name;
      const int j = m.joint_index(name);
      if (j < 1) throw RequestError(field + ": unknown joint '" + name + "'");
      ik::JointReferenceTask t;
      t.joint = j;
      const json* v = &value;
      if (value.is_object()) {
        warn_unknown_keys(value, field, {"value", "gain", "weight"});
        if (!value.contains("value")) throw RequestError(field + "/value: missing");
        v = &value["value"];
        t.gain = number_or(value, "gain", field, ik::kDefaultGain);
        t.weight = number_or(value, "weight", field, t.weight);
      }
      switch (m.joint_type[j]) {
        case core::JointType::kRevolute:
        case core::JointType::kPrismatic: t.q_ref = number(*v, field); break;
        case core::JointType::kSpherical: t.R_ref = quaternion_wxyz(*v, field); break;
        default: throw RequestError(field + ": joint '" + name + "' is " + core::to_string(m.joint_type[j]) +
                                    "; references apply to 1-DOF and spherical joints");
      }
      problem.add(t);
    }
  }
  std::vector<int> drag_ids;
  for (const DragSpec& d : drags) drag_ids.push_back(problem.add(d.task));

  ik::Solver solver(m, settings);
  json out_frames = json::array();
  for (int f = 0; f < frames; ++f) {
    for (size_t k = 0; k < drags.size(); ++k) {
      if (drags[k].release_at == f) problem.remove(drag_ids[k]);
    }
    const ik::Report& rep = solver.step(problem, data, q);
    if (rep.status != ik::Report::Status::kOk) throw RequestError("solver rejected the problem: " + rep.message);
    json frame;
    double drag_error = 0, pin_p = 0, pin_r = 0;
    for (const DragSpec& d : drags) {
      const ik::TaskError e = ik::link_task_error(data, d.task);
      drag_error = std::max(drag_error, d.task.mode == ik::TaskMode::kOrientation ? e.orientation : e.position);
    }
    for (const ik::TaskReport& t : rep.tasks) {
      if (std::string(t.kind) != "pin") continue;
      pin_p = std::max(pin_p, t.position_error);
      pin_r = std::max(pin_r, t.orientation_error);
    }
    frame["drag_error"] = drag_error;
    frame["pin_position_error"] = pin_p;
    frame["pin_orientation_error"] = pin_r;
    frame["joint_speed"] = rep.max_joint_speed;
    frame["limit_violation"] = rep.limit_violation;
    frame["top_rank"] = rep.top_rank;
    frame["microseconds"] = rep.microseconds;
    out_frames.push_back(frame);
  }
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
