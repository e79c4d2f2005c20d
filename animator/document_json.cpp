#include "animator/document_json.hpp"

#include <algorithm>
#include <limits>
#include <optional>

#include "core/configuration.hpp"

namespace animator {

using io::JsonField;
using io::JsonFields;
using nlohmann::json;

namespace {

json vec3(const core::Vector3& v) { return {v.x(), v.y(), v.z()}; }
json quat(const core::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

// saved quaternions are unit to rounding; they are kept bit for bit, and checked to be unit
constexpr double kUnitTolerance = 1e-6;
constexpr std::int64_t kMinInt = std::numeric_limits<int>::min();
constexpr std::int64_t kMaxInt = std::numeric_limits<int>::max();

ik::TaskMode mode_from(JsonFields& f, const JsonField& j) {
  const std::string s = f.string(j);
  const auto mode = ik::task_mode_from_string(s);
  if (!mode) f.fail(j, io::in_quotes(s) + " is not position, orientation or pose");
  return *mode;
}

}  // namespace

// --- settings ----------------------------------------------------------------------------------

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
          {"joint_weights", s.use_joint_weights},
          {"hard_pins", s.hard_pins},
          {"floor", s.floor}};
}

void read_settings(JsonFields& f, const JsonField& j, ik::SolverSettings& s) {
  f.object(j);
  f.refuse_unknown_keys(
      j,
      {"dt", "iterations", "damping", "damping_schedule", "manipulability_threshold", "top_damping",
       "top_singular_value", "range_damping", "max_position_error", "max_orientation_error",
       "limit_margin", "max_joint_step", "joint_weights", "hard_pins", "floor", "gains"});
  s.dt = f.number_or(j["dt"], s.dt);
  s.iterations = static_cast<int>(
      f.integer_or(j["iterations"], s.iterations, ik::kMinIterations, ik::kMaxIterations));
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
  s.hard_pins = f.boolean_or(j["hard_pins"], s.hard_pins);
  s.floor = f.boolean_or(j["floor"], s.floor);
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

void settings_from_json(const json& j, ik::SolverSettings& s) {
  JsonFields f(io::JsonStyle{.base = "settings"});
  io::rethrow_as<SessionError>([&] { read_settings(f, JsonField(j), s); });
  if (const std::string e = ik::validate(s); !e.empty()) throw SessionError("settings: " + e);
}

// --- poses, pins, keys -------------------------------------------------------------------------

json configuration_to_json(const Eigen::VectorXd& q) {
  return std::vector<double>(q.data(), q.data() + q.size());
}

Eigen::VectorXd read_configuration(JsonFields& f, const JsonField& q, const core::Model& m) {
  Eigen::VectorXd v = f.numbers(q, m.nq);
  if (const std::string e = core::check_configuration(m, v); !e.empty()) f.fail(q, e);
  return v;
}

json pins_to_json(const core::Model& m, const std::vector<Pin>& pins) {
  json out = json::array();
  for (const Pin& p : pins) {
    out.push_back({{"link", m.link_name[p.link]},
                   {"mode", ik::to_string(p.mode)},
                   {"point", vec3(p.p_LinkPoint)},
                   {"target", vec3(p.target_W)},
                   {"rotation", quat(p.target_R_W)}});
  }
  return out;
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

json key_to_json(const Keyframe& k) {
  return {{"time", k.time},
          {"q", configuration_to_json(k.q)},
          {"interpolation", to_string(k.interpolation)}};
}

Keyframe read_key(JsonFields& f, const JsonField& key, const core::Model& m) {
  f.object(key);
  const auto interp = interpolation_from_string(f.string(key["interpolation"]));
  if (!interp) f.fail(key["interpolation"], "expected step, linear or smooth");
  return Keyframe{f.number(key["time"]), read_configuration(f, key["q"], m), *interp};
}

// --- clips and layers --------------------------------------------------------------------------

json layer_to_json(const EditLayer& l) {
  json disp = json::array();
  for (const auto& v : l.displacement) disp.push_back(configuration_to_json(v));
  return {{"name", l.name},       {"first_frame", l.first_frame},
          {"falloff", l.falloff}, {"weight", l.weight},
          {"muted", l.muted},     {"displacement", disp}};
}

std::shared_ptr<const EditLayer> read_layer(JsonFields& f,
                                            const JsonField& layer,
                                            const core::Model& m) {
  const JsonField l = f.object(layer);
  auto out = std::make_shared<EditLayer>();
  out->name = f.string(l["name"]);
  out->first_frame = static_cast<int>(f.integer(l["first_frame"], kMinInt, kMaxInt));
  out->falloff = f.number(l["falloff"]);
  out->weight = f.number(l["weight"]);
  out->muted = f.boolean(l["muted"]);
  const JsonField displacement = f.array(l["displacement"]);
  for (std::size_t r = 0; r < displacement.size(); ++r) {
    out->displacement.push_back(f.numbers(displacement[r], m.nv));
  }
  return out;
}

json clip_to_json(const core::Clip& c) {
  json frames = json::array();
  for (const auto& q : c.frames) frames.push_back(configuration_to_json(q));
  return {{"frame_time", c.frame_time}, {"frames", frames}};
}

std::shared_ptr<const core::Clip> read_clip(JsonFields& f,
                                            const JsonField& clip,
                                            const core::Model& m) {
  f.object(clip);
  core::Clip c;
  c.frame_time = f.number(clip["frame_time"]);
  const JsonField frames = f.array(clip["frames"]);
  for (std::size_t k = 0; k < frames.size(); ++k) c.frames.push_back(f.numbers(frames[k], m.nq));
  if (const std::string e = core::check_clip(m, c); !e.empty()) f.fail(clip, e);
  return std::make_shared<const core::Clip>(std::move(c));
}

// --- the markers of a clip's trial -------------------------------------------------------------

namespace {
// more than any marker set in use (Plug-in Gait full body: 39; dense research sets: ~100)
constexpr std::size_t kMaxClipMarkers = 1024;
}  // namespace

json clip_markers_to_json(const core::Model& m, const ClipMarkers& markers) {
  json set = json::array();
  for (const ik::Marker& marker : markers.set.markers) {
    set.push_back({{"name", marker.name},
                   {"link", m.link_name[marker.link]},
                   {"offset", vec3(marker.offset)}});
  }
  const ik::MarkerTrajectories& t = markers.measured;
  json frames = json::array();
  for (int f = 0; f < t.frames; ++f) {
    json row = json::array();
    for (int k = 0; k < t.markers; ++k) {
      const core::Vector3& p = t.frame_positions(f)[k];
      for (int c = 0; c < 3; ++c) row.push_back(t.frame_present(f)[k] ? json(p[c]) : json(nullptr));
    }
    frames.push_back(std::move(row));
  }
  return {{"rate", t.rate_hz}, {"markers", set}, {"frames", frames}};
}

std::shared_ptr<const ClipMarkers> read_clip_markers(JsonFields& f,
                                                     const JsonField& markers,
                                                     const core::Model& m) {
  f.object(markers);
  ik::MarkerSet set;
  const JsonField list = f.array(markers["markers"], kMaxClipMarkers, "markers");
  for (std::size_t k = 0; k < list.size(); ++k) {
    const JsonField entry = f.object(list[k]);
    ik::Marker marker;
    marker.name = f.string(entry["name"]);
    const std::string link = f.string(entry["link"]);
    marker.link = m.link_index(link);
    if (marker.link < 1) f.fail(entry["link"], "unknown link " + io::in_quotes(link));
    marker.offset = f.vector3(entry["offset"]);
    set.markers.push_back(std::move(marker));
  }
  ik::MarkerTrajectories t;
  t.rate_hz = f.number(markers["rate"], {.lo = 0, .hi = 1e6});
  t.markers = set.size();
  const JsonField frames = f.array(markers["frames"]);
  t.frames = static_cast<int>(std::min<std::size_t>(frames.size(), kMaxInt));
  const std::size_t width = 3 * static_cast<std::size_t>(t.markers);
  for (int fr = 0; fr < t.frames; ++fr) {
    const JsonField row = f.array(frames[fr]);
    if (row.size() != width) {
      f.fail(row, "expected " + std::to_string(width) + " numbers or nulls (three per marker)");
    }
    for (int k = 0; k < t.markers; ++k) {
      const JsonField x = row[3 * k], y = row[3 * k + 1], z = row[3 * k + 2];
      const int nulls = int{x->is_null()} + int{y->is_null()} + int{z->is_null()};
      if (nulls == 3) {
        t.positions.push_back(core::Vector3::Zero());
        t.present.push_back(0);
        continue;
      }
      if (nulls != 0) f.fail(row, "marker " + std::to_string(k) + ": part of a sample is null");
      t.positions.emplace_back(f.number(x), f.number(y), f.number(z));
      t.present.push_back(1);
    }
  }
  try {
    return make_clip_markers(m, std::move(set), std::move(t));
  } catch (const std::invalid_argument& e) {
    f.fail(markers, e.what());
  }
}

std::string check_document_markers(const Document& d) {
  if (!d.markers) return {};
  if (!d.clip) return "markers without a clip (rule: markers ride on the clip fitted to them)";
  return check_markers_fit_clip(*d.markers, *d.clip);
}

// --- the BVH source of a character -------------------------------------------------------------

json bvh_source_to_json(const io::BvhLayout& layout) {
  json joints = json::array();
  for (const io::BvhLayout::Joint& joint : layout.joints) {
    json channels = json::array();
    for (const io::BvhChannel c : joint.channels) channels.push_back(io::to_string(c));
    joints.push_back({{"name", joint.name}, {"channels", channels}});
  }
  return {{"scale", layout.scale}, {"joints", joints}};
}

std::shared_ptr<const io::BvhLayout> read_bvh_source(JsonFields& f, const JsonField& j) {
  const JsonField source = f.object(j);
  auto out = std::make_shared<io::BvhLayout>();
  out->scale = f.number(source["scale"]);
  if (!(out->scale > 0)) f.fail(source["scale"], "must be positive (metres per file unit)");
  const JsonField joints = f.array(source["joints"], io::kMaxBvhJoints, "joints");
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const JsonField joint = f.object(joints[k]);
    io::BvhLayout::Joint& out_joint = out->joints.emplace_back();
    out_joint.name = f.string(joint["name"]);
    if (out->find(out_joint.name) != &out_joint) f.fail(joint["name"], "names a joint twice");
    const JsonField channels = f.array(joint["channels"], 6, "channels");
    for (std::size_t c = 0; c < channels.size(); ++c) {
      const std::string name = f.string(channels[c]);
      std::optional<io::BvhChannel> channel;
      for (int v = 0; v < 6; ++v) {
        if (name == io::to_string(static_cast<io::BvhChannel>(v))) {
          channel = static_cast<io::BvhChannel>(v);
        }
      }
      if (!channel) f.fail(channels[c], io::in_quotes(name) + " is not a BVH channel");
      if (std::find(out_joint.channels.begin(), out_joint.channels.end(), *channel) !=
          out_joint.channels.end()) {
        f.fail(channels[c], io::in_quotes(name) + " is listed twice");
      }
      out_joint.channels.push_back(*channel);
    }
  }
  return out;
}

// --- scene and playback ------------------------------------------------------------------------

json scene_to_json(const sim::Scene& scene) {
  json j = json::object();
  for (const sim::Effect e : sim::kAllEffects) j[sim::to_string(e)] = scene.has(e);
  return j;
}

sim::Scene read_scene(JsonFields& f, const JsonField& sc) {
  f.object(sc);
  sim::Scene scene;
  for (const sim::Effect e : sim::kAllEffects) {
    scene.set(e, f.boolean_or(sc[sim::to_string(e)], false));
  }
  return scene;
}

json playback_to_json(const Playback& p) {
  return {{"time", p.time},
          {"speed", p.speed},
          {"loop", p.loop},
          {"loop_start", p.loop_start},
          {"loop_end", p.loop_end}};
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

}  // namespace animator
