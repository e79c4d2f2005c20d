#include "animator/document_changes.hpp"

#include <cstddef>
#include <vector>

#include "animator/document_json.hpp"

namespace animator {

using io::JsonField;
using io::JsonFields;
using nlohmann::json;

namespace {

// entries [at, at + remove) of `a` replaced by [at, at + insert) of `b` give `b`
struct Splice {
  std::size_t at = 0, remove = 0, insert = 0;
  bool empty() const { return remove == 0 && insert == 0; }
};

template <class T, class Same>
Splice splice_between(const std::vector<T>& a, const std::vector<T>& b, Same same) {
  std::size_t prefix = 0;
  while (prefix < a.size() && prefix < b.size() && same(a[prefix], b[prefix])) ++prefix;
  std::size_t suffix = 0;
  while (suffix < a.size() - prefix && suffix < b.size() - prefix &&
         same(a[a.size() - 1 - suffix], b[b.size() - 1 - suffix])) {
    ++suffix;
  }
  return Splice{prefix, a.size() - prefix - suffix, b.size() - prefix - suffix};
}

bool same_playback(const Playback& a, const Playback& b) {
  return a.time == b.time && a.speed == b.speed && a.loop == b.loop &&
         a.loop_start == b.loop_start && a.loop_end == b.loop_end;
}

// the splice of `j` over a list of `size` entries: {"at", "remove", "insert": [...]}
Splice read_splice(JsonFields& f, const JsonField& j, std::size_t size) {
  f.object(j);
  f.refuse_unknown_keys(j, {"at", "remove", "insert"});
  Splice s;
  const auto n = static_cast<std::int64_t>(size);
  s.at = static_cast<std::size_t>(f.integer(j["at"], 0, n));
  s.remove =
      static_cast<std::size_t>(f.integer(j["remove"], 0, n - static_cast<std::int64_t>(s.at)));
  s.insert = f.array(j["insert"]).size();
  return s;
}

void apply_key_splice(JsonFields& f, const JsonField& j, const core::Model& m, KeyTrack& keys) {
  const std::size_t before = keys.keys().size();
  const Splice s = read_splice(f, j, before);
  std::vector<Keyframe> inserted;
  for (std::size_t k = 0; k < s.insert; ++k) inserted.push_back(read_key(f, j["insert"][k], m));
  for (std::size_t k = 0; k < s.remove; ++k) keys.remove(static_cast<int>(s.at));
  for (Keyframe& key : inserted) keys.insert(std::move(key));
  // the track keeps its keys sorted: the inserted ones must land where they were taken from
  bool fits = keys.keys().size() == before - s.remove + s.insert;
  for (std::size_t k = 0; fits && k < s.insert; ++k) {
    fits = keys.keys()[s.at + k].time == j["insert"][k]["time"]->get<double>();
  }
  if (!fits) f.fail(j, "the inserted keys do not fit the track at index " + std::to_string(s.at));
}

void apply_layer_splice(JsonFields& f, const JsonField& j, const core::Model& m, LayerStack& l) {
  const Splice s = read_splice(f, j, l.size());
  LayerStack inserted;
  for (std::size_t k = 0; k < s.insert; ++k) inserted.push_back(read_layer(f, j["insert"][k], m));
  const auto at = l.begin() + static_cast<std::ptrdiff_t>(s.at);
  l.erase(at, at + static_cast<std::ptrdiff_t>(s.remove));
  l.insert(l.begin() + static_cast<std::ptrdiff_t>(s.at), inserted.begin(), inserted.end());
}

}  // namespace

json document_changes(const core::Model& model,
                      const Document& doc0,
                      const Playback& playback0,
                      const Document& doc1,
                      const Playback& playback1) {
  json out = json::object();
  if (doc0.q.size() != doc1.q.size() || doc0.q != doc1.q) {
    out["q"] = configuration_to_json(doc1.q);
  }
  if (doc0.pins != doc1.pins) out["pins"] = pins_to_json(model, doc1.pins);
  const Splice keys = splice_between(doc0.keys.keys(), doc1.keys.keys(),
                                     [](const Keyframe& a, const Keyframe& b) { return a == b; });
  if (!keys.empty()) {
    json inserted = json::array();
    for (std::size_t k = 0; k < keys.insert; ++k) {
      inserted.push_back(key_to_json(doc1.keys.keys()[keys.at + k]));
    }
    out["keys"] = {{"at", keys.at}, {"remove", keys.remove}, {"insert", inserted}};
  }
  if (doc0.clip != doc1.clip) out["clip"] = doc1.clip ? clip_to_json(*doc1.clip) : json(nullptr);
  if (doc0.markers != doc1.markers) {
    out["markers"] = doc1.markers ? clip_markers_to_json(model, *doc1.markers) : json(nullptr);
  }
  // layers are immutable once made: a changed layer is a new object
  const Splice layers =
      splice_between(doc0.layers, doc1.layers, [](const auto& a, const auto& b) { return a == b; });
  if (!layers.empty()) {
    json inserted = json::array();
    for (std::size_t k = 0; k < layers.insert; ++k) {
      inserted.push_back(layer_to_json(*doc1.layers[layers.at + k]));
    }
    out["layers"] = {{"at", layers.at}, {"remove", layers.remove}, {"insert", inserted}};
  }
  const json settings = settings_to_json(doc1.settings);
  if (settings != settings_to_json(doc0.settings)) out["settings"] = settings;
  if (!(doc0.scene == doc1.scene)) out["scene"] = scene_to_json(doc1.scene);
  if (doc0.edit_falloff != doc1.edit_falloff) out["edit_falloff"] = doc1.edit_falloff;
  if (!same_playback(playback0, playback1)) out["playback"] = playback_to_json(playback1);
  return out;
}

void apply_document_changes(const core::Model& model,
                            const json& changes,
                            Document& doc,
                            Playback& playback) {
  Document d = doc;
  Playback p = playback;
  JsonFields f(io::JsonStyle{.root = "/"});
  io::rethrow_as<SessionError>([&] {
    const JsonField c(changes);
    f.object(c);
    f.refuse_unknown_keys(c, {"q", "pins", "keys", "clip", "markers", "layers", "settings", "scene",
                              "edit_falloff", "playback"});
    if (c["q"]) d.q = read_configuration(f, c["q"], model);
    if (c["pins"]) d.pins = read_pins(f, c["pins"], model);
    if (c["keys"]) apply_key_splice(f, c["keys"], model, d.keys);
    if (const JsonField clip = c["clip"]) {
      d.clip = clip->is_null() ? nullptr : read_clip(f, clip, model);
    }
    if (const JsonField markers = c["markers"]) {
      d.markers = markers->is_null() ? nullptr : read_clip_markers(f, markers, model);
    }
    if (const std::string e = check_document_markers(d); !e.empty()) {
      f.fail(c["markers"] ? c["markers"] : c, e);
    }
    if (c["layers"]) apply_layer_splice(f, c["layers"], model, d.layers);
    if (const JsonField settings = c["settings"]) {
      read_settings(f, settings, d.settings);
      if (const std::string e = ik::validate(d.settings); !e.empty()) f.fail(settings, e);
    }
    if (c["scene"]) d.scene = read_scene(f, c["scene"]);
    if (c["edit_falloff"]) d.edit_falloff = f.number(c["edit_falloff"]);
    if (c["playback"]) {
      const bool playing = p.playing;
      p = read_playback(f, c["playback"]);
      p.playing = playing;
    }
  });
  doc = std::move(d);
  playback = p;
}

}  // namespace animator
