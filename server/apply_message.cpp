#include "server/apply_message.hpp"

#include <algorithm>
#include <optional>
#include <string>

#include "animator/session_file.hpp"
#include "server/protocol.hpp"

namespace server {
namespace {

using animator::Session;
using animator::SessionError;

core::Vector3 to_vector3(const Position& p) { return {p[0], p[1], p[2]}; }

std::optional<core::Quaternion> rotation(const std::optional<Rotation>& r) {
  if (!r) return std::nullopt;
  return core::Quaternion((*r)[0], (*r)[1], (*r)[2], (*r)[3]).normalized();
}

// link names are the wire's; the session counts links by index
int link_index(const Session& s, const std::string& name) {
  const int i = s.model().link_index(name);
  if (i < 1) throw SessionError("link", "no link named \"" + name.substr(0, 64) + "\"");
  return i;
}

// --- one Session call per message ------------------------------------------------------------

void run(Session&, const Hello&) {}

void run(Session& s, const DragBegin& m) {
  s.drag_begin(link_index(s, m.link), to_vector3(m.target), to_vector3(m.point));
}

void run(Session& s, const DragMove& m) { s.drag_move(to_vector3(m.target), rotation(m.rotation)); }
void run(Session& s, const DragEnd&) { s.drag_end(); }
void run(Session& s, const Pin& m) { s.pin(link_index(s, m.link), m.mode, to_vector3(m.point)); }
void run(Session& s, const Unpin& m) { s.unpin(link_index(s, m.link)); }

void run(Session& s, const MovePin& m) {
  s.move_pin(link_index(s, m.link), to_vector3(m.target), rotation(m.rotation));
}

void run(Session& s, const SetSettings& m) {
  ik::SolverSettings next = s.solver_settings();
  try {
    animator::settings_from_json(m.settings, next);
  } catch (const SessionError& e) {
    // its what() is a path inside the settings object: "settings/gains/pin: ..."
    throw ProtocolError(std::string(SetSettings::kType) + "." + e.what());
  }
  s.set_solver_settings(next);
}

void run(Session& s, const SetEffects& m) { s.set_scene(m.scene); }
void run(Session& s, const KeyInsert& m) { s.key_insert(m.time, m.interpolation); }
void run(Session& s, const KeyDelete& m) { s.key_delete(m.index); }
void run(Session& s, const KeyMove& m) { s.key_move(m.index, m.time); }
void run(Session& s, const BakeKeys& m) { s.bake_keys(m.rate); }
void run(Session& s, const Record& m) { s.record(m.on); }
void run(Session& s, const Play&) { s.play(); }
void run(Session& s, const Pause&) { s.pause(); }
void run(Session& s, const Seek& m) { s.seek(m.time); }
void run(Session& s, const SetLoop& m) { s.set_loop(m.loop, m.start, m.end); }
void run(Session& s, const SetSpeed& m) { s.set_speed(m.speed); }

void run(Session& s, const Layer& m) {
  // the parser's precedence: remove, else muted, else weight
  if (m.remove) return s.remove_layer(m.index);
  if (m.muted) return s.set_layer_muted(m.index, *m.muted);
  if (m.weight) return s.set_layer_weight(m.index, *m.weight);
  throw ProtocolError("layer.muted: one of muted, weight or remove is required");
}

void run(Session& s, const BakeLayers&) { s.bake_layers(); }
void run(Session& s, const SetFalloff& m) { s.set_edit_falloff(m.seconds); }
void run(Session& s, const Undo&) { s.undo(); }
void run(Session& s, const Redo&) { s.redo(); }

// --- the session's errors in wire terms ------------------------------------------------------

// the message field of a Session argument: the same word but for the frame-named ones
std::string wire_field(const std::string& session_field) {
  if (session_field == "target_W") return "target";
  if (session_field == "p_LinkPoint") return "point";
  return session_field;
}

// "<type>.<field>: <rule>" when the argument at fault is a field of M, else "<type>: <what>"
template <class M>
ProtocolError wire_error(const SessionError& e) {
  const std::string field = wire_field(e.field());
  const bool of_message =
      std::find(M::kFields.begin(), M::kFields.end(), field) != M::kFields.end();
  if (of_message) return ProtocolError(std::string(M::kType) + "." + field + ": " + e.rule());
  return ProtocolError(std::string(M::kType) + ": " + e.what());
}

}  // namespace

void apply(Session& session, const ClientMessage& message) {
  std::visit(
      [&session](const auto& m) {
        using M = std::decay_t<decltype(m)>;
        try {
          run(session, m);
        } catch (const SessionError& e) {
          throw wire_error<M>(e);
        }
      },
      message);
}

}  // namespace server
