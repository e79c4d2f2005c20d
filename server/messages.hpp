// The client messages of the wire protocol (docs/protocol.md "Client → server") as values: one
// struct per message type, its fields named and typed as on the wire, so that a message can be
// logged, compared and replayed (viser `src/viser/_messages.py`; Drake
// `geometry/meshcat_types_internal.h`).
//
// A struct holds what the client sent, validated but not interpreted: links by name, positions
// [x, y, z] and rotations [w, x, y, z] as given (normalized when applied). Reading a text frame
// is parse_client_message (protocol.hpp); running a message on a session is apply()
// (apply_message.hpp); to_json() below writes the text frame back.
#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "animator/keyframes.hpp"
#include "animator/session.hpp"
#include "ik/task.hpp"
#include "sim/scene.hpp"

namespace server {

using Position = std::array<double, 3>;  // [x, y, z] (m)
using Rotation = std::array<double, 4>;  // [w, x, y, z], any nonzero norm
using NoFields = std::array<const char*, 0>;

/// Starts the stream; the connection answers it, not the session.
struct Hello {
  static constexpr const char* kType = "hello";
  static constexpr std::array kFields{"protocol"};
  int protocol = 0;
  bool operator==(const Hello&) const = default;
};

struct DragBegin {
  static constexpr const char* kType = "drag_begin";
  static constexpr std::array kFields{"link", "target", "point"};
  std::string link{};
  Position target{};  // world
  Position point{};   // link frame; absent on the wire: the link origin
  bool operator==(const DragBegin&) const = default;
};

/// The only message that may be superseded by a newer one (latest wins).
struct DragMove {
  static constexpr const char* kType = "drag_move";
  static constexpr std::array kFields{"seq", "target", "rotation"};
  std::uint32_t seq = 0;
  Position target{};  // world, absolute
  std::optional<Rotation> rotation{};
  bool operator==(const DragMove&) const = default;
};

struct DragEnd {
  static constexpr const char* kType = "drag_end";
  static constexpr NoFields kFields{};
  bool operator==(const DragEnd&) const = default;
};

struct Pin {
  static constexpr const char* kType = "pin";
  static constexpr std::array kFields{"link", "mode", "point"};
  std::string link{};
  ik::TaskMode mode = ik::TaskMode::kPosition;  // the default when absent on the wire
  Position point{};
  bool operator==(const Pin&) const = default;
};

struct Unpin {
  static constexpr const char* kType = "unpin";
  static constexpr std::array kFields{"link"};
  std::string link{};
  bool operator==(const Unpin&) const = default;
};

struct MovePin {
  static constexpr const char* kType = "move_pin";
  static constexpr std::array kFields{"link", "target", "rotation"};
  std::string link{};
  Position target{};
  std::optional<Rotation> rotation{};
  bool operator==(const MovePin&) const = default;
};

/// Solver settings by name (docs/ik.md); read by animator::settings_from_json when applied.
struct SetSettings {
  static constexpr const char* kType = "set_settings";
  static constexpr std::array kFields{"settings"};
  nlohmann::json settings = nlohmann::json::object();
  bool operator==(const SetSettings&) const = default;
};

/// Flags absent on the wire are off.
struct SetEffects {
  static constexpr const char* kType = "set_effects";
  static constexpr std::array kFields{"scene"};
  sim::Scene scene{};
  bool operator==(const SetEffects&) const = default;
};

struct KeyInsert {
  static constexpr const char* kType = "key_insert";
  static constexpr std::array kFields{"time", "interpolation"};
  std::optional<double> time{};  // absent: the playback time
  animator::Interpolation interpolation = animator::Interpolation::kSmooth;
  bool operator==(const KeyInsert&) const = default;
};

struct KeyDelete {
  static constexpr const char* kType = "key_delete";
  static constexpr std::array kFields{"index"};
  int index = 0;
  bool operator==(const KeyDelete&) const = default;
};

struct KeyMove {
  static constexpr const char* kType = "key_move";
  static constexpr std::array kFields{"index", "time"};
  int index = 0;
  double time = 0;
  bool operator==(const KeyMove&) const = default;
};

struct BakeKeys {
  static constexpr const char* kType = "bake_keys";
  static constexpr std::array kFields{"rate"};
  double rate = animator::kDefaultClipRate;  // frames per second
  bool operator==(const BakeKeys&) const = default;
};

struct Record {
  static constexpr const char* kType = "record";
  static constexpr std::array kFields{"on"};
  bool on = false;
  bool operator==(const Record&) const = default;
};

struct Play {
  static constexpr const char* kType = "play";
  static constexpr NoFields kFields{};
  bool operator==(const Play&) const = default;
};

struct Pause {
  static constexpr const char* kType = "pause";
  static constexpr NoFields kFields{};
  bool operator==(const Pause&) const = default;
};

struct Seek {
  static constexpr const char* kType = "seek";
  static constexpr std::array kFields{"time"};
  double time = 0;
  bool operator==(const Seek&) const = default;
};

struct SetLoop {
  static constexpr const char* kType = "set_loop";
  static constexpr std::array kFields{"loop", "start", "end"};
  bool loop = true;
  double start = 0;
  double end = -1;  // < 0: the end of the animation
  bool operator==(const SetLoop&) const = default;
};

struct SetSpeed {
  static constexpr const char* kType = "set_speed";
  static constexpr std::array kFields{"speed"};
  double speed = 1;
  bool operator==(const SetSpeed&) const = default;
};

/// One change of edit layer `index`: removed, else muted or unmuted, else reweighted. The
/// parser keeps only the first of these that the message carries.
struct Layer {
  static constexpr const char* kType = "layer";
  static constexpr std::array kFields{"index", "muted", "weight", "remove"};
  int index = 0;
  std::optional<bool> muted{};
  std::optional<double> weight{};
  bool remove = false;
  bool operator==(const Layer&) const = default;
};

struct BakeLayers {
  static constexpr const char* kType = "bake_layers";
  static constexpr NoFields kFields{};
  bool operator==(const BakeLayers&) const = default;
};

struct SetFalloff {
  static constexpr const char* kType = "set_falloff";
  static constexpr std::array kFields{"seconds"};
  double seconds = 0;
  bool operator==(const SetFalloff&) const = default;
};

struct Undo {
  static constexpr const char* kType = "undo";
  static constexpr NoFields kFields{};
  bool operator==(const Undo&) const = default;
};

struct Redo {
  static constexpr const char* kType = "redo";
  static constexpr NoFields kFields{};
  bool operator==(const Redo&) const = default;
};

/// Every client message, in the order of docs/protocol.md.
using ClientMessage = std::variant<Hello,
                                   DragBegin,
                                   DragMove,
                                   DragEnd,
                                   Pin,
                                   Unpin,
                                   MovePin,
                                   SetSettings,
                                   SetEffects,
                                   KeyInsert,
                                   KeyDelete,
                                   KeyMove,
                                   BakeKeys,
                                   Record,
                                   Play,
                                   Pause,
                                   Seek,
                                   SetLoop,
                                   SetSpeed,
                                   Layer,
                                   BakeLayers,
                                   SetFalloff,
                                   Undo,
                                   Redo>;

/// A message with the envelope's `id` (any JSON number or string; null when the client sent
/// none), which the `ack` or `error` answer carries back.
struct ClientRequest {
  ClientMessage message{};
  nlohmann::json id = nullptr;
  bool operator==(const ClientRequest&) const = default;
};

/// The wire type of a message: "drag_move".
const char* message_type(const ClientMessage& message);

/// A message type and its fields (besides `type` and `id`), as the structs above declare them.
struct MessageFields {
  std::string type;
  std::vector<std::string> fields;
  bool operator==(const MessageFields&) const = default;
};
/// Every client message type with its fields, in ClientMessage order (web/js/protocol.js keeps
/// the same table as CLIENT_MESSAGES).
std::vector<MessageFields> client_message_fields();

/// The message as a text frame carries it: `type`, the fields (optional ones only when set).
nlohmann::json to_json(const ClientMessage& message);
/// The same with `id` when the request has one.
nlohmann::json to_json(const ClientRequest& request);

}  // namespace server
