#include "animator/session_file.hpp"

#include <cerrno>
#include <system_error>

#include "animator/document_json.hpp"
#include "io/atomic_file.hpp"
#include "io/character_json.hpp"
#include "io/json_reader.hpp"
#include "io/read_file.hpp"

namespace animator {

using io::JsonField;
using io::JsonFields;
using nlohmann::json;

namespace {

// The document of a session file whose character is `m`; values are kept bit for bit
// (renormalizing a unit quaternion can change its last bit), and checked instead.
Document read_document(JsonFields& f, const JsonField& j, const core::Model& m) {
  Document d;
  d.q = read_configuration(f, j["q"], m);
  d.pins = read_pins(f, j["pins"], m);
  for (std::size_t k = 0; k < f.array(j["keys"]).size(); ++k) {
    d.keys.insert(read_key(f, j["keys"][k], m));
  }
  if (!f.present(j["clip"])->is_null()) d.clip = read_clip(f, j["clip"], m);
  // (files written before markers were kept have no "markers")
  if (const JsonField markers = j["markers"]; markers && !markers->is_null()) {
    d.markers = read_clip_markers(f, markers, m);
    if (const std::string e = check_document_markers(d); !e.empty()) f.fail(markers, e);
  }
  for (std::size_t k = 0; k < f.array(j["layers"]).size(); ++k) {
    d.layers.push_back(read_layer(f, j["layers"][k], m));
  }
  read_settings(f, f.present(j["settings"]), d.settings);
  if (const std::string e = ik::validate(d.settings); !e.empty()) f.fail(j["settings"], e);
  d.scene = read_scene(f, j["scene"]);
  d.edit_falloff = f.number(j["edit_falloff"]);
  return d;
}

}  // namespace

bool SessionWriteError::out_of_space() const {
  return error_ == ENOSPC || error_ == EDQUOT || error_ == EFBIG;
}

SessionImage session_image(const Session& session) {
  return SessionImage{session.model_ptr(), session.character(),  session.document(),
                      session.playback(),  session.bvh_source(), 0};
}

json session_to_json(const SessionImage& image, bool include_character) {
  const Document& d = image.document;
  const core::Model& m = *image.model;
  json keys = json::array();
  for (const Keyframe& k : d.keys.keys()) keys.push_back(key_to_json(k));
  json layers = json::array();
  for (const auto& l : d.layers) layers.push_back(layer_to_json(*l));
  json out = {
      {"format", "pindrag-session"},
      {"version", kSessionFormatVersion},
      {"character_name", image.character},
      {"character", include_character ? json::parse(io::write_character_json(m)) : json(nullptr)},
      {"q", configuration_to_json(d.q)},
      {"pins", pins_to_json(m, d.pins)},
      {"keys", keys},
      {"layers", layers},
      {"settings", settings_to_json(d.settings)},
      {"scene", scene_to_json(d.scene)},
      {"edit_falloff", d.edit_falloff},
      {"playback", playback_to_json(image.playback)},
  };
  out["clip"] = d.clip ? clip_to_json(*d.clip) : json(nullptr);
  out["markers"] = d.markers ? clip_markers_to_json(m, *d.markers) : json(nullptr);
  if (include_character && image.bvh_source) {
    out["bvh_source"] = bvh_source_to_json(*image.bvh_source);
  }
  if (image.journal_seq > 0) out["journal_seq"] = image.journal_seq;
  return out;
}

json session_to_json(const Session& session, bool include_character) {
  return session_to_json(session_image(session), include_character);
}

std::unique_ptr<Session> session_from_json(const json& j,
                                           const std::string& source,
                                           std::uint64_t* journal_seq) {
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
    const auto seq = f.integer_or(doc["journal_seq"], 0, 0, kMaxJournalSeq);
    session->restore(std::move(d), p);
    // files written before BVH sources were kept have none
    if (doc["bvh_source"]) session->set_bvh_source(read_bvh_source(f, doc["bvh_source"]));
    if (journal_seq) *journal_seq = static_cast<std::uint64_t>(seq);
    return session;
  });
}

void save_session(const SessionImage& image, const std::string& path) {
  try {
    io::write_file_atomically(path, session_to_json(image).dump(), 0600);
  } catch (const std::system_error& e) {
    throw SessionWriteError(e.code().value(), e.what());
  }
}

void save_session(const Session& session, const std::string& path) {
  save_session(session_image(session), path);
}

std::unique_ptr<Session> load_session(const std::string& path, std::uint64_t* journal_seq) {
  json j;
  try {
    j = io::read_json_file(path, kSessionJsonLimits, "a session file");
  } catch (const io::FileError& e) {
    throw SessionError(e.what());
  } catch (const io::JsonParseError& e) {
    throw SessionError(e.what());
  }
  return session_from_json(j, path, journal_seq);
}

}  // namespace animator
