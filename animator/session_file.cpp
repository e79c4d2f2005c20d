#include "animator/session_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/atomic_file.hpp"
#include "core/configuration.hpp"
#include "io/character_json.hpp"

namespace animator {

using nlohmann::json;

namespace {

json vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }
json vec3(const core::Vector3& v) { return {v.x(), v.y(), v.z()}; }
json quat(const core::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

// readers that name the field they fail on
const json& at(const json& j, const std::string& key, const std::string& field) {
  if (!j.is_object() || !j.contains(key)) throw SessionError(field + "/" + key + ": missing");
  return j.at(key);
}
double number(const json& j, const std::string& field) {
  if (!j.is_number()) throw SessionError(field + ": expected a number");
  const double x = j.get<double>();
  if (!std::isfinite(x)) throw SessionError(field + ": not finite");
  return x;
}
Eigen::VectorXd read_vec(const json& j, const std::string& field, int size) {
  if (!j.is_array() || (size >= 0 && static_cast<int>(j.size()) != size)) {
    throw SessionError(field + ": expected an array of " + std::to_string(size) + " numbers");
  }
  Eigen::VectorXd v(j.size());
  for (size_t k = 0; k < j.size(); ++k) v[k] = number(j[k], field + "/" + std::to_string(k));
  return v;
}
core::Vector3 read_vec3(const json& j, const std::string& field) { return read_vec(j, field, 3); }
core::Quaternion read_quat(const json& j, const std::string& field) {
  const Eigen::VectorXd v = read_vec(j, field, 4);
  core::Quaternion q(v[0], v[1], v[2], v[3]);
  if (std::abs(q.norm() - 1) > 1e-6) throw SessionError(field + ": not a unit quaternion");
  return q;
}

json clip_to_json(const core::Clip& c) {
  json frames = json::array();
  for (const auto& f : c.frames) frames.push_back(vec(f));
  return {{"frame_time", c.frame_time}, {"frames", frames}};
}

core::Clip clip_from_json(const json& j, const std::string& field, int nq) {
  core::Clip c;
  c.frame_time = number(at(j, "frame_time", field), field + "/frame_time");
  const json& frames = at(j, "frames", field);
  if (!frames.is_array()) throw SessionError(field + "/frames: expected an array");
  for (size_t k = 0; k < frames.size(); ++k) {
    c.frames.push_back(read_vec(frames[k], field + "/frames/" + std::to_string(k), nq));
  }
  return c;
}

const char* mode_name(ik::TaskMode m) { return ik::to_string(m); }
ik::TaskMode mode_from(const json& j, const std::string& field) {
  if (!j.is_string()) throw SessionError(field + ": expected position, orientation or pose");
  const std::string s = j.get<std::string>();
  if (s == "position") return ik::TaskMode::kPosition;
  if (s == "orientation") return ik::TaskMode::kOrientation;
  if (s == "pose") return ik::TaskMode::kPose;
  throw SessionError(field + ": '" + s + "' is not position, orientation or pose");
}

}  // namespace

json settings_to_json(const ik::SolverSettings& s) {
  return {{"dt", s.dt},
          {"iterations", s.iterations},
          {"damping", s.damping},
          {"damping_schedule", ik::to_string(s.damping_schedule)},
          {"manipulability_threshold", s.manipulability_threshold},
          {"top_damping", s.top_damping},
          {"top_singular_value", s.top_singular_value},
          {"range_damping", s.range_damping},
          {"gains", {{"drag", s.drag_gain}, {"pin", s.pin_gain}, {"reference", s.reference_gain},
                     {"limit", s.limit_gain}, {"range", s.range_gain}}},
          {"max_position_error", s.max_position_error},
          {"max_orientation_error", s.max_orientation_error},
          {"limit_margin", s.limit_margin},
          {"max_joint_step", s.max_joint_step},
          {"joint_weights", s.use_joint_weights}};
}

void settings_from_json(const json& j, ik::SolverSettings& s) {
  if (!j.is_object()) throw SessionError("settings: expected an object");
  for (const auto& [key, value] : j.items()) {
    const std::string field = "settings/" + key;
    if (key == "dt") s.dt = number(value, field);
    else if (key == "iterations") {
      if (!value.is_number_integer()) throw SessionError(field + ": expected an integer");
      s.iterations = value.get<int>();
    } else if (key == "damping") s.damping = number(value, field);
    else if (key == "damping_schedule") {
      const auto d = ik::damping_schedule_from_string(value.is_string() ? value.get<std::string>() : "");
      if (!d) throw SessionError(field + ": expected constant, manipulability or residual");
      s.damping_schedule = *d;
    } else if (key == "manipulability_threshold") s.manipulability_threshold = number(value, field);
    else if (key == "top_damping") s.top_damping = number(value, field);
    else if (key == "top_singular_value") s.top_singular_value = number(value, field);
    else if (key == "range_damping") s.range_damping = number(value, field);
    else if (key == "max_position_error") s.max_position_error = number(value, field);
    else if (key == "max_orientation_error") s.max_orientation_error = number(value, field);
    else if (key == "limit_margin") s.limit_margin = number(value, field);
    else if (key == "max_joint_step") s.max_joint_step = number(value, field);
    else if (key == "joint_weights") {
      if (!value.is_boolean()) throw SessionError(field + ": expected true or false");
      s.use_joint_weights = value.get<bool>();
    } else if (key == "gains") {
      if (!value.is_object()) throw SessionError(field + ": expected an object");
      for (const auto& [g, gv] : value.items()) {
        const std::string gf = field + "/" + g;
        if (g == "drag") s.drag_gain = number(gv, gf);
        else if (g == "pin") s.pin_gain = number(gv, gf);
        else if (g == "reference") s.reference_gain = number(gv, gf);
        else if (g == "limit") s.limit_gain = number(gv, gf);
        else if (g == "range") s.range_gain = number(gv, gf);
        else throw SessionError(gf + ": unknown gain (drag, pin, reference, limit, range)");
      }
    } else {
      throw SessionError(field + ": unknown setting");
    }
  }
  if (const std::string e = ik::validate(s); !e.empty()) throw SessionError("settings: " + e);
}

json session_to_json(const Session& session, bool include_character) {
  const Document& d = session.document();
  const core::Model& m = session.model();
  json pins = json::array();
  for (const Pin& p : d.pins) {
    pins.push_back({{"link", m.link_name[p.link]}, {"mode", mode_name(p.mode)}, {"point", vec3(p.p_LinkPoint)},
                    {"target", vec3(p.target_W)}, {"rotation", quat(p.target_R_W)}});
  }
  json keys = json::array();
  for (const Keyframe& k : d.keys.keys()) {
    keys.push_back({{"time", k.time}, {"q", vec(k.q)}, {"interpolation", to_string(k.interpolation)}});
  }
  json layers = json::array();
  for (const auto& l : d.layers) {
    json disp = json::array();
    for (const auto& v : l->displacement) disp.push_back(vec(v));
    layers.push_back({{"name", l->name}, {"first_frame", l->first_frame}, {"falloff", l->falloff},
                      {"weight", l->weight}, {"muted", l->muted}, {"displacement", disp}});
  }
  const Playback& p = session.playback();
  json out = {
      {"format", "pindrag-session"},
      {"version", kSessionFormatVersion},
      {"character_name", session.character()},
      {"character", include_character ? json::parse(io::write_character_json(m)) : json(nullptr)},
      {"q", vec(d.q)},
      {"pins", pins},
      {"keys", keys},
      {"layers", layers},
      {"settings", settings_to_json(d.settings)},
      {"scene", {{"gravity", d.scene.gravity}, {"ground_contact", d.scene.ground_contact},
                 {"dynamic_pins", d.scene.dynamic_pins}, {"hard_limits", d.scene.hard_limits},
                 {"self_collision", d.scene.self_collision}}},
      {"edit_falloff", d.edit_falloff},
      {"playback", {{"time", p.time}, {"speed", p.speed}, {"loop", p.loop},
                    {"loop_start", p.loop_start}, {"loop_end", p.loop_end}}},
  };
  out["clip"] = d.clip ? clip_to_json(*d.clip) : json(nullptr);
  return out;
}

std::unique_ptr<Session> session_from_json(const json& j, const std::string& source) {
  if (!j.is_object() || j.value("format", "") != "pindrag-session") {
    throw SessionError(source + ": not a pindrag session file");
  }
  if (j.value("version", 0) != kSessionFormatVersion) {
    throw SessionError(source + ": session format version " + j.value("version", json(0)).dump() +
                       " is not supported (expected " + std::to_string(kSessionFormatVersion) + ")");
  }
  const io::LoadResult loaded =
      io::load_character_json_string(at(j, "character", "").dump(), source + "#/character", "");
  const core::Model& m = *loaded.model;
  const std::string name = j.value("character_name", m.name);
  auto session = std::make_unique<Session>(loaded.model, name);
  Document d;
  // values are kept bit for bit (renormalizing a unit quaternion can change its last bit); they
  // are checked to be unit instead
  d.q = read_vec(at(j, "q", ""), "/q", m.nq);
  if (const std::string e = core::check_configuration(m, d.q); !e.empty()) throw SessionError("/q: " + e);
  for (size_t k = 0; k < at(j, "pins", "").size(); ++k) {
    const std::string f = "/pins/" + std::to_string(k);
    const json& p = j["pins"][k];
    const std::string link = at(p, "link", f).is_string() ? p["link"].get<std::string>() : "";
    const int i = m.link_index(link);
    if (i < 1) throw SessionError(f + "/link: unknown link '" + link + "'");
    d.pins.push_back(Pin{i, mode_from(at(p, "mode", f), f + "/mode"), read_vec3(at(p, "point", f), f + "/point"),
                         read_vec3(at(p, "target", f), f + "/target"), read_quat(at(p, "rotation", f), f + "/rotation")});
  }
  for (size_t k = 0; k < at(j, "keys", "").size(); ++k) {
    const std::string f = "/keys/" + std::to_string(k);
    const json& key = j["keys"][k];
    const auto interp = interpolation_from_string(at(key, "interpolation", f).is_string() ? key["interpolation"].get<std::string>() : "");
    if (!interp) throw SessionError(f + "/interpolation: expected step, linear or smooth");
    Keyframe kf{number(at(key, "time", f), f + "/time"), read_vec(at(key, "q", f), f + "/q", m.nq), *interp};
    if (const std::string e = core::check_configuration(m, kf.q); !e.empty()) throw SessionError(f + "/q: " + e);
    d.keys.insert(std::move(kf));
  }
  if (!at(j, "clip", "").is_null()) {
    core::Clip c = clip_from_json(j["clip"], "/clip", m.nq);
    if (const std::string e = core::check_clip(m, c); !e.empty()) throw SessionError("/clip: " + e);
    d.clip = std::make_shared<const core::Clip>(std::move(c));
  }
  for (size_t k = 0; k < at(j, "layers", "").size(); ++k) {
    const std::string f = "/layers/" + std::to_string(k);
    const json& l = j["layers"][k];
    auto layer = std::make_shared<EditLayer>();
    layer->name = at(l, "name", f).is_string() ? l["name"].get<std::string>() : "";
    layer->first_frame = static_cast<int>(number(at(l, "first_frame", f), f + "/first_frame"));
    layer->falloff = number(at(l, "falloff", f), f + "/falloff");
    layer->weight = number(at(l, "weight", f), f + "/weight");
    layer->muted = at(l, "muted", f).is_boolean() && l["muted"].get<bool>();
    for (size_t r = 0; r < at(l, "displacement", f).size(); ++r) {
      layer->displacement.push_back(read_vec(l["displacement"][r], f + "/displacement/" + std::to_string(r), m.nv));
    }
    d.layers.push_back(layer);
  }
  settings_from_json(at(j, "settings", ""), d.settings);
  const json& sc = at(j, "scene", "");
  d.scene = Scene{sc.value("gravity", false), sc.value("ground_contact", false), sc.value("dynamic_pins", false),
                  sc.value("hard_limits", false), sc.value("self_collision", false)};
  d.edit_falloff = number(at(j, "edit_falloff", ""), "/edit_falloff");
  const json& pb = at(j, "playback", "");
  Playback p;
  p.time = number(at(pb, "time", "/playback"), "/playback/time");
  p.speed = number(at(pb, "speed", "/playback"), "/playback/speed");
  p.loop = pb.value("loop", true);
  p.loop_start = number(at(pb, "loop_start", "/playback"), "/playback/loop_start");
  p.loop_end = number(at(pb, "loop_end", "/playback"), "/playback/loop_end");
  session->restore(std::move(d), p);
  return session;
}

void write_file_atomically(const std::string& path, const std::string& bytes) {
  try {
    io::write_file_atomically(path, bytes);
  } catch (const std::system_error& e) {
    throw SessionError(e.what());
  }
}

void save_session(const Session& session, const std::string& path) {
  write_file_atomically(path, session_to_json(session).dump());
}

std::unique_ptr<Session> load_session(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SessionError(path + ": cannot open the file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  json j;
  try {
    j = json::parse(buffer.str());
  } catch (const json::parse_error& e) {
    throw SessionError(path + ": invalid JSON at byte " + std::to_string(e.byte));
  }
  return session_from_json(j, path);
}

}  // namespace animator
