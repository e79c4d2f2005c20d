#include "cli/edit_script.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "animator/edit_layer.hpp"
#include "cli/json_fields.hpp"
#include "core/kinematics.hpp"

namespace cli {

namespace {

// most edits, pins per edit and drag keys per edit a script may hold
constexpr std::size_t kMaxEdits = 1000;
constexpr std::size_t kMaxPins = 64;
constexpr std::size_t kMaxKeys = 100000;

const nlohmann::json& member(const nlohmann::json& object, const char* key, const std::string& field) {
  if (!object.contains(key)) throw RequestError(field + "/" + key + ": missing (rule: required)");
  return object.at(key);
}

void require_object(const nlohmann::json& j, const std::string& field) {
  if (!j.is_object()) throw RequestError(field + ": expected an object, got " + std::string(j.type_name()));
}

const nlohmann::json& array_member(const nlohmann::json& object, const char* key,
                                   const std::string& field, std::size_t max) {
  const nlohmann::json& a = member(object, key, field);
  if (!a.is_array()) throw RequestError(field + "/" + key + ": expected an array, got " + std::string(a.type_name()));
  if (a.size() > max) {
    throw RequestError(field + "/" + key + ": " + std::to_string(a.size()) +
                       " entries (rule: at most " + std::to_string(max) + ")");
  }
  return a;
}

int link_named(const nlohmann::json& j, const std::string& field, const core::Model& model) {
  const std::string name = string(j, field);
  const int link = model.link_index(name);
  if (link <= 0) throw RequestError(field + ": unknown link '" + name + "'");
  return link;
}

ik::TaskMode pin_mode(const nlohmann::json& j, const std::string& field) {
  const std::string m = string(j, field);
  if (m == "pose") return ik::TaskMode::kPose;
  if (m == "position") return ik::TaskMode::kPosition;
  throw RequestError(field + ": '" + m + "' (rule: \"pose\" or \"position\")");
}

ScriptPin parse_pin(const nlohmann::json& j, const std::string& field, const core::Model& model) {
  require_object(j, field);
  warn_unknown_keys(j, field, {"link", "mode", "point"});
  ScriptPin p;
  p.link = link_named(member(j, "link", field), field + "/link", model);
  if (j.contains("mode")) p.mode = pin_mode(j["mode"], field + "/mode");
  if (j.contains("point")) p.point = vector3(j["point"], field + "/point");
  return p;
}

ScriptDrag parse_drag(const nlohmann::json& j, const std::string& field, const core::Model& model) {
  require_object(j, field);
  warn_unknown_keys(j, field, {"link", "point", "relative", "keys"});
  ScriptDrag d;
  d.link = link_named(member(j, "link", field), field + "/link", model);
  if (j.contains("point")) d.point = vector3(j["point"], field + "/point");
  if (j.contains("relative")) {
    if (!j["relative"].is_boolean()) throw RequestError(field + "/relative: expected true or false");
    d.relative = j["relative"].get<bool>();
  }
  const nlohmann::json& keys = array_member(j, "keys", field, kMaxKeys);
  if (keys.empty()) throw RequestError(field + "/keys: empty (rule: at least one key)");
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const std::string kf = field + "/keys/" + std::to_string(k);
    require_object(keys[k], kf);
    warn_unknown_keys(keys[k], kf, {"time", "position"});
    DragKey key{number(member(keys[k], "time", kf), kf + "/time"),
                vector3(member(keys[k], "position", kf), kf + "/position")};
    if (!d.keys.empty() && !(key.time > d.keys.back().time)) {
      throw RequestError(kf + "/time: " + std::to_string(key.time) +
                         " (rule: key times strictly increase)");
    }
    d.keys.push_back(key);
  }
  return d;
}

ScriptEdit parse_edit(const nlohmann::json& j, const std::string& field, const core::Model& model) {
  require_object(j, field);
  warn_unknown_keys(j, field, {"start", "end", "pins", "drag"});
  ScriptEdit e;
  e.start = number(member(j, "start", field), field + "/start");
  e.end = number(member(j, "end", field), field + "/end");
  if (e.start < 0) throw RequestError(field + "/start: " + std::to_string(e.start) + " (rule: >= 0)");
  if (!(e.end > e.start)) {
    throw RequestError(field + "/end: " + std::to_string(e.end) + " (rule: after start)");
  }
  if (j.contains("pins")) {
    const nlohmann::json& pins = array_member(j, "pins", field, kMaxPins);
    for (std::size_t k = 0; k < pins.size(); ++k) {
      e.pins.push_back(parse_pin(pins[k], field + "/pins/" + std::to_string(k), model));
    }
  }
  e.drag = parse_drag(member(j, "drag", field), field + "/drag", model);
  for (const ScriptPin& p : e.pins) {
    if (p.link == e.drag.link) {
      throw RequestError(field + "/drag/link: '" + model.link_name[p.link] +
                         "' is pinned in this edit (rule: the dragged link is not pinned)");
    }
  }
  return e;
}

}  // namespace

core::Vector3 ScriptDrag::at(double t) const {
  if (t <= keys.front().time) return keys.front().position;
  if (t >= keys.back().time) return keys.back().position;
  const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                      [](double x, const DragKey& k) { return x < k.time; });
  const auto before = std::prev(after);
  const double s = (t - before->time) / (after->time - before->time);
  return (1 - s) * before->position + s * after->position;
}

EditScript parse_edit_script(const nlohmann::json& j, const core::Model& model) {
  require_object(j, "/");  // the top level
  warn_unknown_keys(j, "", {"falloff", "edits"});
  EditScript s;
  s.falloff = number_or(j, "falloff", "", s.falloff);
  if (s.falloff < 0 || s.falloff > 60) {
    throw RequestError("/falloff: " + std::to_string(s.falloff) + " (rule: in [0, 60] seconds)");
  }
  const nlohmann::json& edits = array_member(j, "edits", "", kMaxEdits);
  if (edits.empty()) throw RequestError("/edits: empty (rule: at least one edit)");
  for (std::size_t k = 0; k < edits.size(); ++k) {
    s.edits.push_back(parse_edit(edits[k], "/edits/" + std::to_string(k), model));
  }
  return s;
}

void run_edit_script(animator::Session& session, const EditScript& script) {
  const core::Model& m = session.model();
  const core::Clip* clip = session.clip();
  if (clip == nullptr || clip->size() < 2) {
    throw RequestError("the clip has fewer than 2 frames: nothing to edit in motion");
  }
  const double ft = clip->frame_time;
  session.set_edit_falloff(script.falloff);
  session.set_loop(false);
  core::Data at_frame(m);
  Eigen::VectorXd q;
  // where the drag target is at frame f: the key trajectory, over the layered clip's point
  auto target = [&](const ScriptDrag& d, int f) {
    core::Vector3 p = d.at(f * ft);
    if (d.relative) {
      animator::layered_frame(m, *session.clip(), session.layers(), f, q);
      core::forward_kinematics(m, at_frame, q);
      p += at_frame.X_W[d.link] * d.point;
    }
    return p;
  };
  for (std::size_t k = 0; k < script.edits.size(); ++k) {
    const ScriptEdit& e = script.edits[k];
    const int first = static_cast<int>(std::lround(e.start / ft));
    const int last = std::min(static_cast<int>(std::lround(e.end / ft)), clip->size() - 1);
    if (first >= last) {
      throw RequestError("/edits/" + std::to_string(k) + "/start: " + std::to_string(e.start) +
                         " s (rule: the window must hold at least one frame after start within "
                         "the clip's " + std::to_string(clip->duration()) + " s)");
    }
    session.seek(first * ft);
    for (const ScriptPin& p : e.pins) session.pin(p.link, p.mode, p.point);
    session.play();
    session.drag_begin(e.drag.link, target(e.drag, first), e.drag.point);
    for (int f = first + 1; f <= last; ++f) {
      session.drag_move(target(e.drag, f));
      // land exactly on frame f (the clock accumulates seconds)
      session.tick(std::max(0.0, f * ft - session.playback().time));
    }
    session.drag_end();
    session.pause();
    for (const ScriptPin& p : e.pins) session.unpin(p.link);
  }
}

}  // namespace cli
