// parse_client_message (protocol.hpp): a text frame to a ClientRequest through io::JsonFields.
// Every refusal names "<type>.<field>" and the rule. Only the syntax and the ranges of
// docs/protocol.md are checked here; link names and indices are checked against the session when
// the message is applied.
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "io/json_parse.hpp"
#include "io/json_reader.hpp"
#include "server/messages.hpp"
#include "server/protocol.hpp"

namespace server {
namespace {

using nlohmann::json;

// Largest coordinate accepted from a client (m); anything beyond is a typo or an attack.
constexpr double kMaxCoordinate = 1e4;
constexpr double kMaxTime = 1e6;
constexpr std::int64_t kMaxIndex = std::numeric_limits<int>::max();
constexpr std::int64_t kMaxU32 = std::numeric_limits<std::uint32_t>::max();

// The fields of one message through the project's JSON reader (io/json_reader.hpp): every
// refusal is "<type>.<field>: <rule>" (JSON pointer in dotted form: "pin.point.0"), numbers are
// range-checked, never wrapped. A field sent as null counts as left out.
class Fields {
 public:
  Fields(const json& message, const std::string& type)
      : root_(message),
        f_(io::JsonStyle{.base = type, .dotted = true, .wording = io::JsonWording::kRequest}) {}

  io::JsonField operator[](const char* field) const { return root_[field]; }
  bool has(const char* field) const { return root_[field].given(); }
  [[noreturn]] void fail(const char* field, const std::string& rule) {
    f_.fail(root_[field], rule);
  }

  double number(const char* field, double lo, double hi) {
    return f_.number(root_[field], {.lo = lo, .hi = hi});
  }
  std::optional<double> optional_number(const char* field, double lo, double hi) {
    if (!has(field)) return std::nullopt;
    return number(field, lo, hi);
  }
  std::int64_t integer(const char* field, std::int64_t lo, std::int64_t hi) {
    return f_.integer(root_[field], lo, hi);
  }
  bool boolean(const char* field) { return f_.boolean(root_[field]); }
  std::string string(const char* field) { return f_.string(root_[field]); }
  // [x, y, z], each within ±kMaxCoordinate
  std::optional<Position> optional_position(const char* field) {
    if (!has(field)) return std::nullopt;
    return position(field);
  }
  Position position(const char* field) {
    const Eigen::VectorXd v = f_.numbers(root_[field], 3, {-kMaxCoordinate, kMaxCoordinate});
    return {v[0], v[1], v[2]};
  }
  // [w, x, y, z] as sent (normalized when applied), of nonzero length
  std::optional<Rotation> optional_rotation(const char* field) {
    if (!has(field)) return std::nullopt;
    const Eigen::VectorXd v = f_.numbers(root_[field], 4);
    if (v.norm() < io::kMinQuaternionNorm) {
      fail(field, "quaternion norm is " + io::message_number(v.norm()) +
                      " (rule: a quaternion [w, x, y, z] of nonzero length)");
    }
    return Rotation{v[0], v[1], v[2], v[3]};
  }
  const json& object(const char* field) { return *f_.object(root_[field]); }
  io::JsonFields& reader() { return f_; }

 private:
  const io::JsonField root_;
  io::JsonFields f_;
};

ik::TaskMode task_mode(Fields& f) {
  if (!f.has("mode")) return ik::TaskMode::kPosition;
  const auto mode = ik::task_mode_from_string(f.string("mode"));
  if (!mode) f.fail("mode", "expected \"position\", \"orientation\" or \"pose\"");
  return *mode;
}

sim::Scene scene_from(Fields& f) {
  io::JsonFields& r = f.reader();
  const io::JsonField j = r.object(f["scene"]);
  sim::Scene scene;
  for (const auto& [key, value] : j->items()) {
    const std::optional<sim::Effect> effect = sim::effect_from_string(key);
    if (!effect) {
      std::string names;
      for (const sim::Effect e : sim::kAllEffects) {
        names += (names.empty() ? "" : ", ") + std::string(sim::to_string(e));
      }
      r.fail(j[key], "unknown key (rule: one of " + names + ")");
    }
    scene.set(*effect, r.boolean(j[key]));
  }
  return scene;
}

// --- one reader per message with fields; fields not in docs/protocol.md are ignored ----------

void read(Fields& f, Hello& m) {
  m.protocol = static_cast<int>(f.integer("protocol", 0, kMaxIndex));
}

void read(Fields& f, DragBegin& m) {
  m.link = f.string("link");
  m.target = f.position("target");
  m.point = f.optional_position("point").value_or(Position{});
}

void read(Fields& f, DragMove& m) {
  m.seq = static_cast<std::uint32_t>(f.integer("seq", 0, kMaxU32));
  m.target = f.position("target");
  m.rotation = f.optional_rotation("rotation");
}

void read(Fields& f, Pin& m) {
  m.link = f.string("link");
  m.mode = task_mode(f);
  m.point = f.optional_position("point").value_or(Position{});
}

void read(Fields& f, Unpin& m) { m.link = f.string("link"); }

void read(Fields& f, MovePin& m) {
  m.link = f.string("link");
  m.target = f.position("target");
  m.rotation = f.optional_rotation("rotation");
}

void read(Fields& f, SetSettings& m) { m.settings = f.object("settings"); }
void read(Fields& f, SetEffects& m) { m.scene = scene_from(f); }

void read(Fields& f, KeyInsert& m) {
  m.time = f.optional_number("time", 0, kMaxTime);
  if (f.has("interpolation")) {
    const auto parsed = animator::interpolation_from_string(f.string("interpolation"));
    if (!parsed) f.fail("interpolation", "expected \"step\", \"linear\" or \"smooth\"");
    m.interpolation = *parsed;
  }
}

void read(Fields& f, KeyDelete& m) { m.index = static_cast<int>(f.integer("index", 0, kMaxIndex)); }

void read(Fields& f, KeyMove& m) {
  m.index = static_cast<int>(f.integer("index", 0, kMaxIndex));
  m.time = f.number("time", 0, kMaxTime);
}

void read(Fields& f, BakeKeys& m) {
  m.rate = f.optional_number("rate", 1, 1000).value_or(animator::kDefaultClipRate);
}

void read(Fields& f, Record& m) { m.on = f.boolean("on"); }
void read(Fields& f, Seek& m) { m.time = f.number("time", -kMaxTime, kMaxTime); }

void read(Fields& f, SetLoop& m) {
  m.loop = f.boolean("loop");
  m.start = f.optional_number("start", 0, kMaxTime).value_or(0);
  m.end = f.optional_number("end", -kMaxTime, kMaxTime).value_or(-1);
}

void read(Fields& f, SetSpeed& m) { m.speed = f.number("speed", -100, 100); }

void read(Fields& f, Layer& m) {
  m.index = static_cast<int>(f.integer("index", 0, kMaxIndex));
  if (f.has("remove")) {
    if (!f.boolean("remove")) f.fail("remove", "expected true when present");
    m.remove = true;
  } else if (f.has("muted")) {
    m.muted = f.boolean("muted");
  } else if (f.has("weight")) {
    m.weight = f.number("weight", -10, 10);
  } else {
    f.fail("muted", "one of muted, weight or remove is required");
  }
}

void read(Fields& f, SetFalloff& m) { m.seconds = f.number("seconds", 0, 3600); }

// messages without fields: nothing to read
template <class M>
requires(M::kFields.empty()) void read(Fields&, M&) {}

// the ClientMessage alternative whose kType is `type`, read from `f`; nullopt when none is
template <std::size_t... I>
std::optional<ClientMessage> read_message(std::string_view type,
                                          Fields& f,
                                          std::index_sequence<I...>) {
  std::optional<ClientMessage> out;
  auto try_type = [&](auto type_tag) {
    using M = typename decltype(type_tag)::type;
    if (out || type != M::kType) return;
    M m;
    read(f, m);
    out = std::move(m);
  };
  (try_type(std::type_identity<std::variant_alternative_t<I, ClientMessage>>{}), ...);
  return out;
}

}  // namespace

ClientRequest parse_client_message(std::string_view text) {
  json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw ProtocolError("message: not valid JSON");
  if (!j.is_object()) throw ProtocolError("message: must be a JSON object with a \"type\"");
  // the id the answer carries back: a number or a string, else none
  const auto id_it = j.find("id");
  const json id = id_it != j.end() && (id_it->is_number() || id_it->is_string()) ? *id_it : json();
  const auto type_it = j.find("type");
  if (type_it == j.end() || !type_it->is_string()) {
    throw ProtocolError("message.type: is required and must be a string", id);
  }
  if (id_it != j.end() && id.is_null() && !id_it->is_null()) {
    throw ProtocolError("message.id: must be a number or a string");
  }
  const std::string& type = type_it->get_ref<const std::string&>();
  Fields fields(j, type);
  try {
    std::optional<ClientMessage> message =
        read_message(type, fields, std::make_index_sequence<std::variant_size_v<ClientMessage>>{});
    if (!message) {
      throw ProtocolError("type: unknown message type \"" + type.substr(0, 64) + "\"", id);
    }
    return ClientRequest{std::move(*message), id};
  } catch (const io::JsonFieldError& e) {
    throw ProtocolError(e.what(), id);
  }
}

}  // namespace server
