#include "animator/session_file.hpp"

#include <limits>
#include <system_error>

#include "core/configuration.hpp"
#include "io/atomic_file.hpp"
#include "io/character_json.hpp"
#include "io/json_reader.hpp"
#include "io/read_file.hpp"

namespace animator {

using io::JsonField;
using io::JsonFields;
using nlohmann::json;

namespace {

json vec(const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); }
json vec3(const core::Vector3& v) { return {v.x(), v.y(), v.z()}; }
json quat(const core::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

// Sessions embed a character (up to 64 MiB) and clips and edit layers of any length; the caps
// only keep a damaged or hostile file from costing unbounded memory.
constexpr io::JsonLimits kSessionLimits{.max_bytes = std::size_t{1} << 30,
                                        .max_depth = io::kMaxJsonDepth,
                                        .max_values = std::size_t{1} << 27};
// saved quaternions are unit to rounding; they are kept bit for bit, and checked to be unit
constexpr double kUnitTolerance = 1e-6;
constexpr std::int64_t kMinInt = std::numeric_limits<int>::min();
constexpr std::int64_t kMaxInt = std::numeric_limits<int>::max();

json clip_to_json(const core::Clip& c) {
  json frames = json::array();
  for (const auto& f : c.frames) frames.push_back(vec(f));
  return {{"frame_time", c.frame_time}, {"frames", frames}};
}

core::Clip clip_from_json(JsonFields& f, const JsonField& j, int nq) {
  core::Clip c;
  c.frame_time = f.number(j["frame_time"]);
  const JsonField frames = f.array(j["frames"]);
  for (std::size_t k = 0; k < frames.size(); ++k) c.frames.push_back(f.numbers(frames[k], nq));
  return c;
}

ik::TaskMode mode_from(JsonFields& f, const JsonField& j) {
  const std::string s = f.string(j);
  const auto mode = ik::task_mode_from_string(s);
  if (!mode) f.fail(j, io::in_quotes(s) + " is not position, orientation or pose");
  return *mode;
}

// the keys present in `j` over `s`
void read_settings(JsonFields& f, const JsonField& j, ik::SolverSettings& s) {
  f.object(j);
  f.refuse_unknown_keys(
      j, {"dt", "iterations", "damping", "damping_schedule", "manipulability_threshold",
          "top_damping", "top_singular_value", "range_damping", "max_position_error",
          "max_orientation_error", "limit_margin", "max_joint_step", "joint_weights", "gains"});
  s.dt = f.number_or(j["dt"], s.dt);
  s.iterations = static_cast<int>(f.integer_or(j["iterations"], s.iterations, kMinInt, kMaxInt));
  s.damping = f.number_or(j["damping"], s.damping);
  if (const JsonField d = j["damping_schedule"]) {
    const auto schedule = ik::damping_schedule_from_string(f.string(d));
    if (!schedule) f.fail(d, "expected constant, manipulability or residual");
    s.damping_schedule = *schedule;
  }
  s.manipulability_threshold =
      f.number_or(j["manipulability_threshold"], s.manipulability_threshold);
  s.top_damping = f.number_or(j["top_damping"], s.top_damping);
  s.top_singular_value = f.number_or(j["top_singular_value"], s.top_singular_value);
  s.range_damping = f.number_or(j["range_damping"], s.range_damping);
  s.max_position_error = f.number_or(j["max_position_error"], s.max_position_error);
  s.max_orientation_error = f.number_or(j["max_orientation_error"], s.max_orientation_error);
  s.limit_margin = f.number_or(j["limit_margin"], s.limit_margin);
  s.max_joint_step = f.number_or(j["max_joint_step"], s.max_joint_step);
  s.use_joint_weights = f.boolean_or(j["joint_weights"], s.use_joint_weights);
  if (const JsonField g = j["gains"]) {
    f.object(g);
    f.refuse_unknown_keys(g, {"drag", "pin", "reference", "limit", "range"});
    s.drag_gain = f.number_or(g["drag"], s.drag_gain);
    s.pin_gain = f.number_or(g["pin"], s.pin_gain);
    s.reference_gain = f.number_or(g["reference"], s.reference_gain);
    s.limit_gain = f.number_or(g["limit"], s.limit_gain);
    s.range_gain = f.number_or(g["range"], s.range_gain);
  }
}

std::vector<Pin> read_pins(JsonFields& f, const JsonField& pins, const core::Model& m) {
  std::vector<Pin> out;
  for (std::size_t k = 0; k < f.array(pins).size(); ++k) {
    const JsonField p = f.object(pins[k]);
    const std::string link = f.string(p["link"]);
    const int i = m.link_index(link);
    if (i < 1) f.fail(p["link"], "unknown link " + io::in_quotes(link));
    out.push_back(Pin{i, mode_from(f, p["mode"]), f.vector3(p["point"]), f.vector3(p["target"]),
                      f.quaternion(p["rotation"], kUnitTolerance)});
  }
  return out;
}

// a configuration of `m` (nq numbers) that passes core::check_configuration
Eigen::VectorXd read_configuration(JsonFields& f, const JsonField& q, const core::Model& m) {
  Eigen::VectorXd v = f.numbers(q, m.nq);
  if (const std::string e = core::check_configuration(m, v); !e.empty()) f.fail(q, e);
  return v;
}

void read_keys(JsonFields& f, const JsonField& keys, const core::Model& m, KeyTrack& out) {
  for (std::size_t k = 0; k < f.array(keys).size(); ++k) {
    const JsonField key = f.object(keys[k]);
    const auto interp = interpolation_from_string(f.string(key["interpolation"]));
    if (!interp) f.fail(key["interpolation"], "expected step, linear or smooth");
    out.insert(Keyframe{f.number(key["time"]), read_configuration(f, key["q"], m), *interp});
  }
}

LayerStack read_layers(JsonFields& f, const JsonField& layers, const core::Model& m) {
  LayerStack out;
  for (std::size_t k = 0; k < f.array(layers).size(); ++k) {
    const JsonField l = f.object(layers[k]);
    auto layer = std::make_shared<EditLayer>();
    layer->name = f.string(l["name"]);
    layer->first_frame = static_cast<int>(f.integer(l["first_frame"], kMinInt, kMaxInt));
    layer->falloff = f.number(l["falloff"]);
    layer->weight = f.number(l["weight"]);
    layer->muted = f.boolean(l["muted"]);
    const JsonField displacement = f.array(l["displacement"]);
    for (std::size_t r = 0; r < displacement.size(); ++r) {
      layer->displacement.push_back(f.numbers(displacement[r], m.nv));
    }
    out.push_back(layer);
  }
  return out;
}

sim::Scene read_scene(JsonFields& f, const JsonField& sc) {
  f.object(sc);
  sim::Scene scene;
  for (const sim::Effect e : sim::kAllEffects) {
    scene.set(e, f.boolean_or(sc[sim::to_string(e)], false));
  }
  return scene;
}

Playback read_playback(JsonFields& f, const JsonField& pb) {
  f.object(pb);
  Playback p;
  p.time = f.number(pb["time"]);
  p.speed = f.number(pb["speed"]);
  p.loop = f.boolean_or(pb["loop"], true);
  p.loop_start = f.number(pb["loop_start"]);
  p.loop_end = f.number(pb["loop_end"]);
  return p;
}

// The document of a session file whose character is `m`; values are kept bit for bit
// (renormalizing a unit quaternion can change its last bit), and checked instead.
Document read_document(JsonFields& f, const JsonField& j, const core::Model& m) {
  Document d;
  d.q = read_configuration(f, j["q"], m);
  d.pins = read_pins(f, j["pins"], m);
  read_keys(f, j["keys"], m, d.keys);
  if (!f.present(j["clip"])->is_null()) {
    core::Clip c = clip_from_json(f, j["clip"], m.nq);
    if (const std::string e = core::check_clip(m, c); !e.empty()) f.fail(j["clip"], e);
    d.clip = std::make_shared<const core::Clip>(std::move(c));
  }
  d.layers = read_layers(f, j["layers"], m);
  read_settings(f, f.present(j["settings"]), d.settings);
  if (const std::string e = ik::validate(d.settings); !e.empty()) f.fail(j["settings"], e);
  d.scene = read_scene(f, j["scene"]);
  d.edit_falloff = f.number(j["edit_falloff"]);
  return d;
}

}  // namespace

json scene_to_json(const sim::Scene& scene) {
  json j = json::object();
  for (const sim::Effect e : sim::kAllEffects) j[sim::to_string(e)] = scene.has(e);
  return j;
}

json settings_to_json(const ik::SolverSettings& s) {
  return {{"dt", s.dt},
          {"iterations", s.iterations},
          {"damping", s.damping},
          {"damping_schedule", ik::to_string(s.damping_schedule)},
          {"manipulability_threshold", s.manipulability_threshold},
          {"top_damping", s.top_damping},
          {"top_singular_value", s.top_singular_value},
          {"range_damping", s.range_damping},
          {"gains",
           {{"drag", s.drag_gain},
            {"pin", s.pin_gain},
            {"reference", s.reference_gain},
            {"limit", s.limit_gain},
            {"range", s.range_gain}}},
          {"max_position_error", s.max_position_error},
          {"max_orientation_error", s.max_orientation_error},
          {"limit_margin", s.limit_margin},
          {"max_joint_step", s.max_joint_step},
          {"joint_weights", s.use_joint_weights}};
}

void settings_from_json(const json& j, ik::SolverSettings& s) {
  JsonFields f(io::JsonStyle{.base = "settings"});
  io::rethrow_as<SessionError>([&] { read_settings(f, JsonField(j), s); });
  if (const std::string e = ik::validate(s); !e.empty()) throw SessionError("settings: " + e);
}

json session_to_json(const Session& session, bool include_character) {
  const Document& d = session.document();
  const core::Model& m = session.model();
  json pins = json::array();
  for (const Pin& p : d.pins) {
    pins.push_back({{"link", m.link_name[p.link]},
                    {"mode", ik::to_string(p.mode)},
                    {"point", vec3(p.p_LinkPoint)},
                    {"target", vec3(p.target_W)},
                    {"rotation", quat(p.target_R_W)}});
  }
  json keys = json::array();
  for (const Keyframe& k : d.keys.keys()) {
    keys.push_back(
        {{"time", k.time}, {"q", vec(k.q)}, {"interpolation", to_string(k.interpolation)}});
  }
  json layers = json::array();
  for (const auto& l : d.layers) {
    json disp = json::array();
    for (const auto& v : l->displacement) disp.push_back(vec(v));
    layers.push_back({{"name", l->name},
                      {"first_frame", l->first_frame},
                      {"falloff", l->falloff},
                      {"weight", l->weight},
                      {"muted", l->muted},
                      {"displacement", disp}});
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
      {"scene", scene_to_json(d.scene)},
      {"edit_falloff", d.edit_falloff},
      {"playback",
       {{"time", p.time},
        {"speed", p.speed},
        {"loop", p.loop},
        {"loop_start", p.loop_start},
        {"loop_end", p.loop_end}}},
  };
  out["clip"] = d.clip ? clip_to_json(*d.clip) : json(nullptr);
  return out;
}

std::unique_ptr<Session> session_from_json(const json& j, const std::string& source) {
  const JsonField doc(j);
  const JsonField format = doc["format"], version = doc["version"];
  if (!format || !format->is_string() || *format != "pindrag-session") {
    throw SessionError(source + ": not a pindrag session file");
  }
  if (!version || *version != kSessionFormatVersion) {
    throw SessionError(source + ": session format version " + (version ? version->dump() : "0") +
                       " is not supported (expected " + std::to_string(kSessionFormatVersion) +
                       ")");
  }
  JsonFields f(io::JsonStyle{.root = "/"});
  const std::string character =
      io::rethrow_as<SessionError>([&] { return f.present(doc["character"])->dump(); });
  const io::LoadResult loaded =
      io::load_character_json_string(character, source + "#/character", "");
  const core::Model& m = *loaded.model;
  return io::rethrow_as<SessionError>([&] {
    const std::string name = doc["character_name"] ? f.string(doc["character_name"]) : m.name;
    auto session = std::make_unique<Session>(loaded.model, name);
    Document d = read_document(f, doc, m);
    const Playback p = read_playback(f, doc["playback"]);
    session->restore(std::move(d), p);
    return session;
  });
}

void save_session(const Session& session, const std::string& path) {
  try {
    io::write_file_atomically(path, session_to_json(session).dump());
  } catch (const std::system_error& e) {
    throw SessionError(e.what());
  }
}

std::unique_ptr<Session> load_session(const std::string& path) {
  json j;
  try {
    j = io::read_json_file(path, kSessionLimits, "a session file");
  } catch (const io::FileError& e) {
    throw SessionError(e.what());
  } catch (const io::JsonParseError& e) {
    throw SessionError(e.what());
  }
  return session_from_json(j, path);
}

}  // namespace animator
