#include "cli/simulate_scene.hpp"

#include <algorithm>
#include <chrono>

#include "cli/json_fields.hpp"
#include "core/configuration.hpp"
#include "io/bundled_characters.hpp"
#include "sim/placement.hpp"
#include "sim/props.hpp"

namespace cli {

namespace {

using core::Quaternion;
using core::Vector3;
using io::JsonField;
using io::JsonFields;
using nlohmann::json;

constexpr double kMaxCoordinate = 1e4;  // m
constexpr double kMaxSpeed = 1e3;       // m/s or rad/s
constexpr double kMaxDuration = 3600;   // s
constexpr std::size_t kMaxBodies = 1000;

const io::NumberRange kCoordinate{-kMaxCoordinate, kMaxCoordinate};
const io::NumberRange kSpeed{-kMaxSpeed, kMaxSpeed};
const io::NumberRange kPositive{1e-9, 1e6};
const io::NumberRange kGain{0, 1e12};

sim::Integrator integrator_from(JsonFields& f, const JsonField& field) {
  const std::string name = f.string(field);
  for (sim::Integrator i :
       {sim::Integrator::kImplicit, sim::Integrator::kSemiImplicit, sim::Integrator::kRk4}) {
    if (name == sim::to_string(i)) return i;
  }
  f.fail(field, io::in_quotes(name) + " is not one of implicit, semi_implicit, rk4");
}

sim::WorldSettings world_settings_from(JsonFields& f, const JsonField& root) {
  sim::WorldSettings s;
  s.step = f.number_or(root["dt"], s.step, {1e-6, 0.1});
  if (root["integrator"]) s.integrator = integrator_from(f, root["integrator"]);
  if (const JsonField c = root["contact"]) {
    f.object(c);
    f.refuse_unknown_keys(c, {"kp", "kd", "mu_static", "mu_dynamic", "kfp", "kfd", "smoothing"});
    sim::ContactSettings& k = s.contact;
    k.kp = f.number_or(c["kp"], k.kp, kGain);
    k.kd = f.number_or(c["kd"], k.kd, kGain);
    k.mu_static = f.number_or(c["mu_static"], k.mu_static, {0, 10});
    k.mu_dynamic = f.number_or(c["mu_dynamic"], k.mu_dynamic, {0, 10});
    k.kfp = f.number_or(c["kfp"], k.kfp, kGain);
    k.kfd = f.number_or(c["kfd"], k.kfd, kGain);
    k.smoothing = f.number_or(c["smoothing"], k.smoothing, {1e-6, 1e3});
    if (k.mu_dynamic > k.mu_static) f.fail(c["mu_dynamic"], "must not exceed mu_static");
  }
  return s;
}

Vector3 unit_vector(JsonFields& f, const JsonField& field) {
  const Vector3 v = f.vector3(field, kCoordinate);
  if (std::abs(v.norm() - 1) > 1e-6) f.fail(field, "must be a unit vector");
  return v;
}

sim::Environment environment_from(JsonFields& f, const JsonField& root) {
  sim::Environment e;
  if (const JsonField g = root["ground"]) {
    f.object(g);
    f.refuse_unknown_keys(g, {"normal", "point"});
    if (g["normal"]) e.ground.normal = unit_vector(f, g["normal"]);
    if (g["point"]) e.ground.point = f.vector3(g["point"], kCoordinate);
  }
  if (const JsonField boxes = root["static_boxes"]) {
    f.array(boxes, kMaxBodies, "static boxes");
    for (std::size_t k = 0; k < boxes.size(); ++k) {
      const JsonField b = boxes[k];
      f.object(b);
      f.refuse_unknown_keys(b, {"size", "position", "rotation"});
      sim::StaticBox box;
      box.half_extents = 0.5 * f.vector3(b["size"], kPositive);
      if (b["position"]) box.pose.p = f.vector3(b["position"], kCoordinate);
      if (b["rotation"]) box.pose.R = f.quaternion(b["rotation"]).toRotationMatrix();
      e.boxes.push_back(box);
    }
  }
  return e;
}

sim::PropShape shape_from(JsonFields& f, const JsonField& b) {
  sim::PropShape s;
  const JsonField shape = b["shape"];
  const std::string kind = f.string(shape);
  if (kind == "box") {
    s.shape = core::Geometry::Shape::kBox;
    s.size = f.vector3(b["size"], kPositive);
  } else if (kind == "sphere") {
    s.shape = core::Geometry::Shape::kSphere;
    s.radius = f.number(b["radius"], kPositive);
  } else if (kind == "capsule") {
    s.shape = core::Geometry::Shape::kCapsule;
    s.radius = f.number(b["radius"], kPositive);
    s.length = f.number(b["length"], {0, 1e6});
  } else {
    f.fail(shape, io::in_quotes(kind) + " is not one of box, sphere, capsule");
  }
  return s;
}

void add_prop(JsonFields& f, const JsonField& b, sim::World& world) {
  f.object(b);
  f.refuse_unknown_keys(b, {"name", "shape", "size", "radius", "length", "mass", "position",
                            "rotation", "velocity", "angular_velocity"});
  const std::string name = f.string(b["name"]);
  if (name.empty() || world.body_index(name) >= 0) {
    f.fail(b["name"], "must be a unique, non-empty body name");
  }
  const sim::PropShape shape = shape_from(f, b);
  const double mass = f.number(b["mass"], kPositive);
  auto model = sim::make_prop(name, shape, mass);
  Eigen::VectorXd q = core::neutral_configuration(*model);
  if (b["position"]) q.head<3>() = f.vector3(b["position"], kCoordinate);
  const Quaternion R = b["rotation"] ? f.quaternion(b["rotation"]) : Quaternion::Identity();
  core::set_quaternion_at(q, 3, R);
  // a free joint's velocity is its body twist [ω; v] in body axes; the file gives world axes
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6);
  if (b["angular_velocity"]) {
    v.head<3>() = R.conjugate() * f.vector3(b["angular_velocity"], kSpeed);
  }
  if (b["velocity"]) v.tail<3>() = R.conjugate() * f.vector3(b["velocity"], kSpeed);
  world.add_body(name, model, q, v);
}

json vec(const Vector3& v) { return json::array({v.x(), v.y(), v.z()}); }

json body_json(const sim::Body& b) {
  if (b.model->joint_type[1] != core::JointType::kFree) return {{"name", b.name}};
  const Quaternion R = core::quaternion_at(b.q, 3);
  const core::Transform X = b.model->X_PJ[1];
  return {{"name", b.name},
          {"p", vec(X * Vector3(b.q.head<3>()))},
          {"rotation", json::array({R.w(), R.x(), R.y(), R.z()})},
          {"v", vec(X.R * (R * Vector3(b.v.segment<3>(3))))},
          {"w", vec(X.R * (R * Vector3(b.v.head<3>())))}};
}

json frame_json(const sim::World& w) {
  json frame = {{"t", w.time()}, {"energy", w.energy()}};
  json& bodies = frame["bodies"] = json::array();
  for (int i = 0; i < w.body_count(); ++i) bodies.push_back(body_json(w.body(i)));
  json& contacts = frame["contacts"] = json::array();
  for (const sim::ContactPair& p : w.contact_pairs()) {
    const sim::Body& b = w.body(p.body);
    contacts.push_back({{"body", b.name},
                        {"link", b.model->link_name[p.link]},
                        {"point", vec(p.ref_W)},
                        {"force", vec(p.wrench.tail<3>())},
                        {"moment", vec(p.wrench.head<3>())}});
  }
  return frame;
}

}  // namespace

sim::Scene read_effects(io::JsonFields& f, const io::JsonField& effects) {
  std::vector<std::string> names;
  if (!effects) return {};
  f.array(effects, 16, "effects");
  for (std::size_t k = 0; k < effects.size(); ++k) {
    const std::string name = f.string(effects[k]);
    if (!sim::effect_from_string(name)) {
      f.fail(effects[k], io::in_quotes(name) +
                             " is not an effect (rule: one of gravity, ground_contact, "
                             "friction, hard_limits, self_collision, dynamic_pins)");
    }
    names.push_back(name);
  }
  return sim::Scene::from_names(names);
}

SimulationRun read_simulation_scene(const json& doc) {
  return io::rethrow_as<RequestError>([&] {
    JsonFields f = request_fields();
    const JsonField root(doc);
    f.object(root);
    f.refuse_unknown_keys(root, {"character", "bodies", "ground", "static_boxes", "effects",
                                 "contact", "integrator", "dt", "duration", "record_every"});
    SimulationRun run;
    try {
      run.world =
          std::make_unique<sim::World>(world_settings_from(f, root), environment_from(f, root));
    } catch (const sim::SimError& e) {
      f.fail(root, e.what());
    }
    sim::World& world = *run.world;
    if (const JsonField c = root["character"]; c.given()) {
      try {
        auto model = io::load_character(f.string(c)).model;
        // standing on the ground: the rest pose, its lowest collision point on the plane
        const Eigen::VectorXd q = sim::place_on_ground(*model, core::rest_configuration(*model),
                                                       world.environment().ground);
        world.add_body(model->name, model, q);
      } catch (const core::ModelError& e) {
        f.fail(c, e.what());
      }
    }
    if (const JsonField bodies = root["bodies"]) {
      f.array(bodies, kMaxBodies, "bodies");
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        try {
          add_prop(f, bodies[k], world);
        } catch (const core::ModelError& e) {
          f.fail(bodies[k], e.what());
        } catch (const sim::SimError& e) {
          f.fail(bodies[k], e.what());
        }
      }
    }
    world.set_scene(read_effects(f, root["effects"]));
    run.duration = f.number_or(root["duration"], run.duration, {0, kMaxDuration});
    run.record_every = static_cast<int>(f.integer_or(root["record_every"], 10, 1, 1'000'000));
    return run;
  });
}

json run_simulation(SimulationRun& run) {
  sim::World& w = *run.world;
  const auto steps = static_cast<long long>(std::llround(run.duration / w.settings().step));
  json frames = json::array({frame_json(w)});
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(std::min<long long>(steps, 1'000'000)));
  for (long long k = 1; k <= steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    w.step();
    const double dt =
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    if (us.size() < us.capacity()) us.push_back(dt);
    if (k % run.record_every == 0) frames.push_back(frame_json(w));
  }
  json stages = json::object();
  for (int s = 0; s < sim::kStageCount; ++s) {
    stages[sim::to_string(static_cast<sim::Stage>(s))] = w.counters()[static_cast<sim::Stage>(s)];
  }
  double median = 0;
  if (!us.empty()) {
    std::nth_element(us.begin(), us.begin() + static_cast<long>(us.size() / 2), us.end());
    median = us[us.size() / 2];
  }
  return {{"frames", frames},
          {"stages", stages},
          {"us_per_step", median},
          {"effects", [&] {
             json e = json::array();
             for (sim::Effect x : w.scene().effects()) e.push_back(sim::to_string(x));
             return e;
           }()}};
}

}  // namespace cli
