#include "cli/edit_script.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

#include "animator/edit_layer.hpp"
#include "cli/json_fields.hpp"
#include "core/kinematics.hpp"

namespace cli {

namespace {

using io::JsonField;
using io::JsonFields;

// most edits, pins per edit and drag keys per edit a script may hold
constexpr std::size_t kMaxEdits = 1000;
constexpr std::size_t kMaxPins = 64;
constexpr std::size_t kMaxKeys = 100000;

int link_named(JsonFields& f, const JsonField& field, const core::Model& model) {
  const std::string name = f.string(field);
  const int link = model.link_index(name);
  if (link <= 0) f.fail(field, "unknown link " + io::in_quotes(name));
  return link;
}

// a pin of an edit holds its position, or its whole pose
ik::TaskMode pin_mode(JsonFields& f, const JsonField& field) {
  const std::string m = f.string(field);
  const auto mode = ik::task_mode_from_string(m);
  if (!mode || *mode == ik::TaskMode::kOrientation) {
    f.fail(field, io::in_quotes(m) + " (rule: \"pose\" or \"position\")");
  }
  return *mode;
}

ScriptPin parse_pin(JsonFields& f, const JsonField& j, const core::Model& model) {
  f.object(j);
  f.warn_unknown_keys(j, {"link", "mode", "point"});
  ScriptPin p;
  p.link = link_named(f, j["link"], model);
  if (j["mode"]) p.mode = pin_mode(f, j["mode"]);
  if (j["point"]) p.point = f.vector3(j["point"]);
  return p;
}

ScriptDrag parse_drag(JsonFields& f, const JsonField& j, const core::Model& model) {
  f.object(j);
  f.warn_unknown_keys(j, {"link", "point", "relative", "keys"});
  ScriptDrag d;
  d.link = link_named(f, j["link"], model);
  if (j["point"]) d.point = f.vector3(j["point"]);
  d.relative = f.boolean_or(j["relative"], d.relative);
  const JsonField keys = f.array(j["keys"], kMaxKeys, "entries");
  if (keys.size() == 0) f.fail(keys, "empty (rule: at least one key)");
  for (std::size_t k = 0; k < keys.size(); ++k) {
    const JsonField key = f.object(keys[k]);
    f.warn_unknown_keys(key, {"time", "position"});
    const DragKey parsed{f.number(key["time"]), f.vector3(key["position"])};
    if (!d.keys.empty() && !(parsed.time > d.keys.back().time)) {
      f.fail(key["time"], io::message_number(parsed.time) + " (rule: key times strictly increase)");
    }
    d.keys.push_back(parsed);
  }
  return d;
}

ScriptEdit parse_edit(JsonFields& f, const JsonField& j, const core::Model& model) {
  f.object(j);
  f.warn_unknown_keys(j, {"start", "end", "pins", "drag"});
  ScriptEdit e;
  e.start = f.number(j["start"], {.lo = 0});
  e.end = f.number(j["end"]);
  if (!(e.end > e.start)) f.fail(j["end"], io::message_number(e.end) + " (rule: after start)");
  if (const JsonField pins = j["pins"]) {
    for (std::size_t k = 0; k < f.array(pins, kMaxPins, "entries").size(); ++k) {
      e.pins.push_back(parse_pin(f, pins[k], model));
    }
  }
  e.drag = parse_drag(f, j["drag"], model);
  for (const ScriptPin& p : e.pins) {
    if (p.link == e.drag.link) {
      f.fail(j["drag"]["link"],
             io::in_quotes(model.link_name[p.link]) +
                 " is pinned in this edit (rule: the dragged link is not pinned)");
    }
  }
  return e;
}

EditScript parse_script(JsonFields& f, const JsonField& j, const core::Model& model) {
  f.object(j);
  f.warn_unknown_keys(j, {"falloff", "edits"});
  EditScript s;
  s.falloff = f.number_or(j["falloff"], s.falloff, {.lo = 0, .hi = 60});  // seconds
  const JsonField edits = f.array(j["edits"], kMaxEdits, "entries");
  if (edits.size() == 0) f.fail(edits, "empty (rule: at least one edit)");
  for (std::size_t k = 0; k < edits.size(); ++k) {
    s.edits.push_back(parse_edit(f, edits[k], model));
  }
  return s;
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
  JsonFields f = request_fields();
  return io::rethrow_as<RequestError>([&] { return parse_script(f, JsonField(j), model); });
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
                         "the clip's " +
                         std::to_string(clip->duration()) + " s)");
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
