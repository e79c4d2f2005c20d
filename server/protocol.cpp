#include "server/protocol.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "animator/session_file.hpp"

namespace server {
namespace {

using nlohmann::json;

// Largest coordinate accepted from a client (m); anything beyond is a typo or an attack.
constexpr double kMaxCoordinate = 1e4;
constexpr double kMaxTime = 1e6;

json vec3(const core::Vector3& v) { return json::array({v.x(), v.y(), v.z()}); }
json quat(const core::Quaternion& q) { return json::array({q.w(), q.x(), q.y(), q.z()}); }

// Reads fields of one message; every error names "<type>.<field>" and the rule.
class Fields {
 public:
  Fields(const json& message, std::string type) : m_(message), type_(std::move(type)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& rule) const {
    throw ProtocolError(type_ + "." + field + ": " + rule, id());
  }
  json id() const {
    const auto it = m_.find("id");
    if (it == m_.end() || !(it->is_number() || it->is_string())) return nullptr;
    return *it;
  }
  bool has(const char* field) const { return m_.contains(field) && !m_[field].is_null(); }
  const json& get(const char* field) const {
    if (!has(field)) fail(field, "is required");
    return m_[field];
  }
  double number(const char* field, double lo, double hi) const {
    const json& v = get(field);
    if (!v.is_number()) fail(field, "must be a number");
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < lo || d > hi) {
      fail(field, "must be a finite number in [" + fmt(lo) + ", " + fmt(hi) + "]");
    }
    return d;
  }
  std::optional<double> optional_number(const char* field, double lo, double hi) const {
    if (!has(field)) return std::nullopt;
    return number(field, lo, hi);
  }
  int integer(const char* field, int lo, int hi) const {
    const json& v = get(field);
    if (!v.is_number_integer()) fail(field, "must be an integer");
    const auto i = v.get<std::int64_t>();
    if (i < lo || i > hi) fail(field, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return static_cast<int>(i);
  }
  bool boolean(const char* field) const {
    const json& v = get(field);
    if (!v.is_boolean()) fail(field, "must be true or false");
    return v.get<bool>();
  }
  const std::string& string(const char* field) const {
    const json& v = get(field);
    if (!v.is_string()) fail(field, "must be a string");
    return v.get_ref<const std::string&>();
  }
  core::Vector3 vector3(const char* field) const {
    const json& v = get(field);
    if (!v.is_array() || v.size() != 3) fail(field, "must be an array of 3 numbers [x, y, z]");
    core::Vector3 out;
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number()) fail(field, "must be an array of 3 numbers [x, y, z]");
      out[k] = v[k].get<double>();
      if (!std::isfinite(out[k]) || std::abs(out[k]) > kMaxCoordinate) {
        fail(field, "components must be finite and within ±" + fmt(kMaxCoordinate) + " m");
      }
    }
    return out;
  }
  std::optional<core::Quaternion> optional_rotation(const char* field) const {
    if (!has(field)) return std::nullopt;
    const json& v = get(field);
    if (!v.is_array() || v.size() != 4) fail(field, "must be a quaternion [w, x, y, z]");
    double c[4];
    for (int k = 0; k < 4; ++k) {
      if (!v[k].is_number()) fail(field, "must be a quaternion [w, x, y, z]");
      c[k] = v[k].get<double>();
      if (!std::isfinite(c[k])) fail(field, "components must be finite");
    }
    core::Quaternion q(c[0], c[1], c[2], c[3]);
    if (q.norm() < 1e-6) fail(field, "must not be the zero quaternion");
    q.normalize();
    return q;
  }
  int link(const core::Model& model, const char* field = "link") const {
    const std::string& name = string(field);
    const int i = model.link_index(name);
    if (i < 1) fail(field, "no link named \"" + name.substr(0, 64) + "\"");
    return i;
  }
  const json& object(const char* field) const {
    const json& v = get(field);
    if (!v.is_object()) fail(field, "must be an object");
    return v;
  }

 private:
  static std::string fmt(double d) {
    std::string s = std::to_string(d);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  }
  const json& m_;
  std::string type_;
};

ik::TaskMode task_mode(const Fields& f) {
  if (!f.has("mode")) return ik::TaskMode::kPosition;
  const std::string& mode = f.string("mode");
  if (mode == "position") return ik::TaskMode::kPosition;
  if (mode == "orientation") return ik::TaskMode::kOrientation;
  if (mode == "pose") return ik::TaskMode::kPose;
  f.fail("mode", "must be \"position\", \"orientation\" or \"pose\"");
}

animator::Scene scene_from(const Fields& f, const json& j) {
  animator::Scene scene;
  const std::pair<const char*, bool animator::Scene::*> flags[] = {
      {"gravity", &animator::Scene::gravity},
      {"ground_contact", &animator::Scene::ground_contact},
      {"dynamic_pins", &animator::Scene::dynamic_pins},
      {"hard_limits", &animator::Scene::hard_limits},
      {"self_collision", &animator::Scene::self_collision}};
  for (const auto& [name, member] : flags) {
    if (!j.contains(name)) continue;
    if (!j[name].is_boolean()) f.fail(std::string("scene.") + name, "must be true or false");
    scene.*member = j[name].get<bool>();
  }
  for (const auto& [key, value] : j.items()) {
    bool known = false;
    for (const auto& flag : flags) known = known || key == flag.first;
    if (!known) f.fail("scene." + key.substr(0, 64), "is not a scene effect");
  }
  return scene;
}

SessionEdit parse_edit(const std::string& type, const Fields& f, const core::Model& model) {
  using animator::Session;
  if (type == "drag_begin") {
    const int link = f.link(model);
    const core::Vector3 target = f.vector3("target");
    const core::Vector3 point = f.has("point") ? f.vector3("point") : core::Vector3::Zero();
    return [=](Session& s) { s.drag_begin(link, target, point); };
  }
  if (type == "drag_end") return [](Session& s) { s.drag_end(); };
  if (type == "pin") {
    const int link = f.link(model);
    const ik::TaskMode mode = task_mode(f);
    const core::Vector3 point = f.has("point") ? f.vector3("point") : core::Vector3::Zero();
    return [=](Session& s) { s.pin(link, mode, point); };
  }
  if (type == "unpin") {
    const int link = f.link(model);
    return [=](Session& s) { s.unpin(link); };
  }
  if (type == "move_pin") {
    const int link = f.link(model);
    const core::Vector3 target = f.vector3("target");
    const auto rotation = f.optional_rotation("rotation");
    return [=](Session& s) { s.move_pin(link, target, rotation); };
  }
  if (type == "set_settings") {
    const json settings = f.object("settings");
    return [settings](Session& s) {
      ik::SolverSettings next = s.solver_settings();
      animator::settings_from_json(settings, next);
      s.set_solver_settings(next);
    };
  }
  if (type == "set_effects") {
    const animator::Scene scene = scene_from(f, f.object("scene"));
    return [=](Session& s) { s.set_scene(scene); };
  }
  if (type == "key_insert") {
    const auto time = f.optional_number("time", 0, kMaxTime);
    animator::Interpolation interpolation = animator::Interpolation::kSmooth;
    if (f.has("interpolation")) {
      const auto parsed = animator::interpolation_from_string(f.string("interpolation"));
      if (!parsed) f.fail("interpolation", "must be \"step\", \"linear\" or \"smooth\"");
      interpolation = *parsed;
    }
    return [=](Session& s) { s.key_insert(time, interpolation); };
  }
  if (type == "key_delete") {
    const int index = f.integer("index", 0, std::numeric_limits<int>::max());
    return [=](Session& s) { s.key_delete(index); };
  }
  if (type == "key_move") {
    const int index = f.integer("index", 0, std::numeric_limits<int>::max());
    const double time = f.number("time", 0, kMaxTime);
    return [=](Session& s) { s.key_move(index, time); };
  }
  if (type == "bake_keys") {
    const double rate = f.optional_number("rate", 1, 1000).value_or(animator::kDefaultClipRate);
    return [=](Session& s) { s.bake_keys(rate); };
  }
  if (type == "record") {
    const bool on = f.boolean("on");
    return [=](Session& s) { s.record(on); };
  }
  if (type == "play") return [](Session& s) { s.play(); };
  if (type == "pause") return [](Session& s) { s.pause(); };
  if (type == "seek") {
    const double time = f.number("time", -kMaxTime, kMaxTime);
    return [=](Session& s) { s.seek(time); };
  }
  if (type == "set_loop") {
    const bool loop = f.boolean("loop");
    const double start = f.optional_number("start", 0, kMaxTime).value_or(0);
    const double end = f.optional_number("end", -kMaxTime, kMaxTime).value_or(-1);
    return [=](Session& s) { s.set_loop(loop, start, end); };
  }
  if (type == "set_speed") {
    const double speed = f.number("speed", -100, 100);
    return [=](Session& s) { s.set_speed(speed); };
  }
  if (type == "layer") {
    const int index = f.integer("index", 0, std::numeric_limits<int>::max());
    if (f.has("remove")) {
      if (!f.boolean("remove")) f.fail("remove", "must be true when present");
      return [=](Session& s) { s.remove_layer(index); };
    }
    if (f.has("muted")) {
      const bool muted = f.boolean("muted");
      return [=](Session& s) { s.set_layer_muted(index, muted); };
    }
    if (f.has("weight")) {
      const double weight = f.number("weight", -10, 10);
      return [=](Session& s) { s.set_layer_weight(index, weight); };
    }
    f.fail("muted", "one of muted, weight or remove is required");
  }
  if (type == "bake_layers") return [](Session& s) { s.bake_layers(); };
  if (type == "set_falloff") {
    const double seconds = f.number("seconds", 0, 3600);
    return [=](Session& s) { s.set_edit_falloff(seconds); };
  }
  if (type == "undo") return [](Session& s) { s.undo(); };
  if (type == "redo") return [](Session& s) { s.redo(); };
  throw ProtocolError("type: unknown message type \"" + type.substr(0, 64) + "\"", f.id());
}

json limits_json(const core::Model& model, int i) {
  const core::JointType t = model.joint_type[i];
  if (t != core::JointType::kRevolute && t != core::JointType::kPrismatic) return nullptr;
  const core::JointLimits& l = model.limits[i];
  if (!std::isfinite(l.lower) || !std::isfinite(l.upper)) return nullptr;
  return json::array({l.lower, l.upper});
}

json range_json(const core::Model& model, int i) {
  if (model.joint_type[i] != core::JointType::kSpherical) return nullptr;
  const core::SphericalRange& r = model.spherical_range[i];
  if (r.empty()) return nullptr;
  json vertices = json::array();
  for (size_t k = 0; k < r.swing.size(); ++k) {
    vertices.push_back({r.swing[k].x(), r.swing[k].y(), r.twist_lower[k], r.twist_upper[k]});
  }
  json triangles = json::array();
  for (const auto& t : r.triangles) triangles.push_back({t[0], t[1], t[2]});
  return {{"frame", quat(r.frame)}, {"vertices", vertices}, {"triangles", triangles}};
}

json shapes_json(const core::Model& model, int i) {
  // visual primitives, else collision ones (as the thumbnail renderer draws them)
  auto primitive = [](const core::Geometry& g) { return g.shape != core::Geometry::Shape::kMesh; };
  const std::vector<core::Geometry>* list = &model.visual[i];
  if (std::none_of(list->begin(), list->end(), primitive)) list = &model.collision[i];
  json shapes = json::array();
  for (const core::Geometry& g : *list) {
    if (!primitive(g)) continue;
    shapes.push_back({{"shape", core::to_string(g.shape)},
                      {"radius", g.radius},
                      {"length", g.length},
                      {"size", vec3(g.size)},
                      {"p", vec3(g.X_LinkShape.p)},
                      {"R", quat(core::Quaternion(g.X_LinkShape.R))}});
  }
  return shapes;
}

void put_u16(std::string& b, size_t at, std::uint16_t v) { std::memcpy(b.data() + at, &v, 2); }
void put_u32(std::string& b, size_t at, std::uint32_t v) { std::memcpy(b.data() + at, &v, 4); }
void put_f32(std::string& b, size_t at, double v) {
  const auto f = static_cast<float>(v);
  std::memcpy(b.data() + at, &f, 4);
}

}  // namespace

ClientMessage parse_client_message(std::string_view text, const core::Model& model) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw ProtocolError("message: not valid JSON");
  if (!j.is_object()) throw ProtocolError("message: must be a JSON object with a \"type\"");
  const auto type_it = j.find("type");
  Fields any(j, "message");
  if (type_it == j.end() || !type_it->is_string()) {
    throw ProtocolError("message.type: is required and must be a string", any.id());
  }
  if (j.contains("id") && !(j["id"].is_number() || j["id"].is_string() || j["id"].is_null())) {
    throw ProtocolError("message.id: must be a number or a string");
  }
  ClientMessage out;
  out.type = type_it->get<std::string>();
  out.id = any.id();
  Fields f(j, out.type);
  if (out.type == "hello") {
    out.protocol = f.integer("protocol", 0, std::numeric_limits<int>::max());
  } else if (out.type == DragMove::kType) {
    DragMove d;
    const json& seq = f.get("seq");
    if (!seq.is_number_unsigned() || seq.get<std::uint64_t>() > 0xFFFFFFFFull) {
      f.fail("seq", "must be an unsigned 32-bit integer");
    }
    d.seq = static_cast<std::uint32_t>(seq.get<std::uint64_t>());
    d.target = f.vector3("target");
    d.rotation = f.optional_rotation("rotation");
    out.drag_move = d;
  } else {
    out.edit = parse_edit(out.type, f, model);
  }
  return out;
}

json character_json(const core::Model& model, const std::string& name, bool skinned) {
  json links = json::array();
  double lowest = 0, highest = 0;
  for (int i = 1; i < model.njoints; ++i) {
    links.push_back({{"name", model.link_name[i]},
                     {"display_name", model.display_name[i]},
                     {"parent", model.parent[i] - 1},
                     {"joint", model.joint_name[i]},
                     {"joint_type", core::to_string(model.joint_type[i])},
                     {"X_PJ", {{"p", vec3(model.X_PJ[i].p)}, {"R", quat(core::Quaternion(model.X_PJ[i].R))}}},
                     {"axis", vec3(model.axis[i])},
                     {"limits", limits_json(model, i)},
                     {"range", range_json(model, i)},
                     {"shapes", shapes_json(model, i)}});
  }
  // height of the neutral figure: its vertical extent over the link origins
  std::vector<core::Transform> X_W(model.njoints);
  for (int i = 1; i < model.njoints; ++i) {
    X_W[i] = X_W[model.parent[i]] * model.X_PJ[i];
    lowest = i == 1 ? X_W[i].p.y() : std::min(lowest, X_W[i].p.y());
    highest = i == 1 ? X_W[i].p.y() : std::max(highest, X_W[i].p.y());
  }
  return {{"name", name}, {"links", links}, {"height", highest - lowest}, {"skinned", skinned}};
}

json state_json(const animator::Session& s, const std::string& session_id) {
  const core::Model& m = s.model();
  const core::Data& data = s.kinematics();
  json links = json::array();
  for (int i = 1; i < m.njoints; ++i) {
    links.push_back({{"name", m.link_name[i]}, {"p", vec3(data.X_W[i].p)}, {"R", quat(core::Quaternion(data.X_W[i].R))}});
  }
  json pins = json::array();
  for (const animator::Pin& p : s.pins()) {
    pins.push_back({{"link", m.link_name[p.link]},
                    {"mode", ik::to_string(p.mode)},
                    {"point", vec3(p.p_LinkPoint)},
                    {"target", vec3(p.target_W)},
                    {"rotation", quat(p.target_R_W)}});
  }
  json keys = json::array();
  for (const animator::Keyframe& k : s.keys().keys()) {
    keys.push_back({{"time", k.time}, {"interpolation", animator::to_string(k.interpolation)}});
  }
  json clip = nullptr;
  if (const core::Clip* c = s.clip()) {
    clip = {{"frames", c->size()}, {"frame_time", c->frame_time}, {"duration", c->duration()}};
  }
  json layers = json::array();
  for (const auto& layer : s.layers()) {
    layers.push_back({{"name", layer->name},
                      {"first_frame", layer->first_frame},
                      {"last_frame", layer->last_frame()},
                      {"weight", layer->weight},
                      {"muted", layer->muted},
                      {"falloff", layer->falloff}});
  }
  const animator::Playback& pb = s.playback();
  const animator::Scene& sc = s.scene();
  return {{"protocol", kProtocolVersion},
          {"session", session_id},
          {"q", std::vector<double>(s.q().data(), s.q().data() + s.q().size())},
          {"links", links},
          {"pins", pins},
          {"keys", keys},
          {"clip", clip},
          {"layers", layers},
          {"playback",
           {{"time", pb.time}, {"playing", pb.playing}, {"speed", pb.speed}, {"loop", pb.loop},
            {"loop_start", pb.loop_start}, {"loop_end", pb.loop_end}, {"duration", s.duration()}}},
          {"recording", s.recording()},
          {"settings", animator::settings_to_json(s.solver_settings())},
          {"scene",
           {{"gravity", sc.gravity}, {"ground_contact", sc.ground_contact}, {"dynamic_pins", sc.dynamic_pins},
            {"hard_limits", sc.hard_limits}, {"self_collision", sc.self_collision}}},
          {"falloff", s.edit_falloff()},
          {"undo",
           {{"can_undo", s.history().can_undo()},
            {"can_redo", s.history().can_redo()},
            {"labels", s.history().undo_labels()}}}};
}

json snapshot_json(const animator::Session& s, const std::string& session_id) {
  json j = state_json(s, session_id);
  j["character"] = character_json(s.model(), s.character(), s.skin() != nullptr);
  return j;
}

json report_json(const ik::Report& r) {
  double drag_error = 0, pin_position = 0, pin_orientation = 0;
  for (const ik::TaskReport& t : r.tasks) {
    const std::string_view kind = t.kind;
    if (kind == "drag") drag_error = std::max(drag_error, t.position_error);
    if (kind == "pin") {
      pin_position = std::max(pin_position, t.position_error);
      pin_orientation = std::max(pin_orientation, t.orientation_error);
    }
  }
  return {{"type", "report"},
          {"microseconds", r.microseconds},
          {"drag_error", drag_error},
          {"pin_position_error", pin_position},
          {"pin_orientation_error", pin_orientation},
          {"joint_speed", r.max_joint_speed},
          {"limit_violation", r.limit_violation},
          {"top_rank", r.top_rank}};
}

std::string ack_message(const json& id, const std::string& request) {
  return json{{"type", "ack"}, {"id", id}, {"request", request}}.dump();
}

std::string error_message(const json& id, const std::string& message) {
  json j{{"type", "error"}, {"message", message}};
  if (!id.is_null()) j["id"] = id;
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string encode_pose_frame(const animator::Session& s, std::uint32_t frame_id, std::uint32_t last_seq) {
  const core::Model& m = s.model();
  const core::Data& data = s.kinematics();
  const int n = m.nlinks();
  std::string b(kPoseHeaderBytes + kPoseBytesPerLink * static_cast<size_t>(n), '\0');
  put_u32(b, 0, kPoseMagic);
  put_u16(b, 4, static_cast<std::uint16_t>(kProtocolVersion));
  put_u16(b, 6, static_cast<std::uint16_t>(n));
  put_u32(b, 8, frame_id);
  put_u32(b, kPoseSeqOffset, last_seq);
  const double time = s.playback().time;
  std::memcpy(b.data() + 16, &time, 8);
  const core::Vector3 root = n > 0 ? data.X_W[1].p : core::Vector3::Zero();
  for (int k = 0; k < 3; ++k) put_f32(b, 24 + 4 * static_cast<size_t>(k), root[k]);
  size_t at = kPoseHeaderBytes;
  for (int i = 1; i <= n; ++i) {
    const core::Quaternion world(data.X_W[i].R);
    // the joint's own rotation: the link in its parent, with the joint placement taken out
    const core::Quaternion own(core::Matrix3(m.X_PJ[i].R.transpose() * data.X_P[i].R));
    const double values[11] = {data.X_W[i].p.x(), data.X_W[i].p.y(), data.X_W[i].p.z(),
                               world.w(), world.x(), world.y(), world.z(),
                               own.w(), own.x(), own.y(), own.z()};
    for (double v : values) {
      put_f32(b, at, v);
      at += 4;
    }
  }
  return b;
}

void set_pose_frame_seq(std::string& frame, std::uint32_t last_seq) {
  if (frame.size() >= kPoseHeaderBytes) put_u32(frame, kPoseSeqOffset, last_seq);
}

}  // namespace server
