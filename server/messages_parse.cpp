// parse_client_message (protocol.hpp): a text frame to a ClientRequest. Every refusal names
// "<type>.<field>" and the rule. Only the syntax and the ranges of docs/protocol.md are checked
// here; link names and indices are checked against the session when the message is applied.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <utility>

#include "server/messages.hpp"
#include "server/protocol.hpp"

namespace server {
namespace {

using nlohmann::json;

// Largest coordinate accepted from a client (m); anything beyond is a typo or an attack.
constexpr double kMaxCoordinate = 1e4;
constexpr double kMaxTime = 1e6;
constexpr int kMaxIndex = std::numeric_limits<int>::max();

// Reads fields of one message; every error names "<type>.<field>" and the rule.
class Fields {
 public:
  Fields(const json& message, std::string type) : m_(message), type_(std::move(type)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& rule) const {
    throw ProtocolError(type_ + "." + field + ": " + rule, id());
  }
  json id() const {
    const auto it = m_.find("id");
    if (it == m_.end() || !(it->is_number() || it->is_string())) return nullptr;
    return *it;
  }
  bool has(const char* field) const { return m_.contains(field) && !m_[field].is_null(); }
  const json& get(const char* field) const {
    if (!has(field)) fail(field, "is required");
    return m_[field];
  }
  double number(const char* field, double lo, double hi) const {
    const json& v = get(field);
    if (!v.is_number()) fail(field, "must be a number");
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < lo || d > hi) {
      fail(field, "must be a finite number in [" + fmt(lo) + ", " + fmt(hi) + "]");
    }
    return d;
  }
  std::optional<double> optional_number(const char* field, double lo, double hi) const {
    if (!has(field)) return std::nullopt;
    return number(field, lo, hi);
  }
  int integer(const char* field, int lo, int hi) const {
    const json& v = get(field);
    if (!v.is_number_integer()) fail(field, "must be an integer");
    const auto i = v.get<std::int64_t>();
    if (i < lo || i > hi) {
      fail(field, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
    return static_cast<int>(i);
  }
  std::uint32_t u32(const char* field) const {
    const json& v = get(field);
    if (!v.is_number_unsigned() || v.get<std::uint64_t>() > 0xFFFFFFFFull) {
      fail(field, "must be an unsigned 32-bit integer");
    }
    return static_cast<std::uint32_t>(v.get<std::uint64_t>());
  }
  bool boolean(const char* field) const {
    const json& v = get(field);
    if (!v.is_boolean()) fail(field, "must be true or false");
    return v.get<bool>();
  }
  const std::string& string(const char* field) const {
    const json& v = get(field);
    if (!v.is_string()) fail(field, "must be a string");
    return v.get_ref<const std::string&>();
  }
  Position position(const char* field) const {
    const json& v = get(field);
    if (!v.is_array() || v.size() != 3) fail(field, "must be an array of 3 numbers [x, y, z]");
    Position out;
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number()) fail(field, "must be an array of 3 numbers [x, y, z]");
      out[k] = v[k].get<double>();
      if (!std::isfinite(out[k]) || std::abs(out[k]) > kMaxCoordinate) {
        fail(field, "components must be finite and within ±" + fmt(kMaxCoordinate) + " m");
      }
    }
    return out;
  }
  std::optional<Position> optional_position(const char* field) const {
    if (!has(field)) return std::nullopt;
    return position(field);
  }
  // as sent; normalized when applied
  std::optional<Rotation> optional_rotation(const char* field) const {
    if (!has(field)) return std::nullopt;
    const json& v = get(field);
    if (!v.is_array() || v.size() != 4) fail(field, "must be a quaternion [w, x, y, z]");
    Rotation q;
    double norm2 = 0;
    for (int k = 0; k < 4; ++k) {
      if (!v[k].is_number()) fail(field, "must be a quaternion [w, x, y, z]");
      q[k] = v[k].get<double>();
      if (!std::isfinite(q[k])) fail(field, "components must be finite");
      norm2 += q[k] * q[k];
    }
    if (std::sqrt(norm2) < 1e-6) fail(field, "must not be the zero quaternion");
    return q;
  }
  const json& object(const char* field) const {
    const json& v = get(field);
    if (!v.is_object()) fail(field, "must be an object");
    return v;
  }

 private:
  static std::string fmt(double d) {
    std::string s = std::to_string(d);
    s.erase(s.find_last_not_of('0') + 1);
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s;
  }
  const json& m_;
  std::string type_;
};

ik::TaskMode task_mode(const Fields& f) {
  if (!f.has("mode")) return ik::TaskMode::kPosition;
  const std::string& mode = f.string("mode");
  if (mode == "position") return ik::TaskMode::kPosition;
  if (mode == "orientation") return ik::TaskMode::kOrientation;
  if (mode == "pose") return ik::TaskMode::kPose;
  f.fail("mode", "must be \"position\", \"orientation\" or \"pose\"");
}

sim::Scene scene_from(const Fields& f, const json& j) {
  sim::Scene scene;
  for (const auto& [key, value] : j.items()) {
    const std::optional<sim::Effect> effect = sim::effect_from_string(key);
    if (!effect) f.fail("scene." + key.substr(0, 64), "is not a scene effect");
    if (!value.is_boolean()) f.fail("scene." + key, "must be true or false");
    scene.set(*effect, value.get<bool>());
  }
  return scene;
}

// --- one reader per message with fields; fields not in docs/protocol.md are ignored ----------

void read(const Fields& f, Hello& m) { m.protocol = f.integer("protocol", 0, kMaxIndex); }

void read(const Fields& f, DragBegin& m) {
  m.link = f.string("link");
  m.target = f.position("target");
  m.point = f.optional_position("point").value_or(Position{});
}

void read(const Fields& f, DragMove& m) {
  m.seq = f.u32("seq");
  m.target = f.position("target");
  m.rotation = f.optional_rotation("rotation");
}

void read(const Fields& f, Pin& m) {
  m.link = f.string("link");
  m.mode = task_mode(f);
  m.point = f.optional_position("point").value_or(Position{});
}

void read(const Fields& f, Unpin& m) { m.link = f.string("link"); }

void read(const Fields& f, MovePin& m) {
  m.link = f.string("link");
  m.target = f.position("target");
  m.rotation = f.optional_rotation("rotation");
}

void read(const Fields& f, SetSettings& m) { m.settings = f.object("settings"); }
void read(const Fields& f, SetEffects& m) { m.scene = scene_from(f, f.object("scene")); }

void read(const Fields& f, KeyInsert& m) {
  m.time = f.optional_number("time", 0, kMaxTime);
  if (f.has("interpolation")) {
    const auto parsed = animator::interpolation_from_string(f.string("interpolation"));
    if (!parsed) f.fail("interpolation", "must be \"step\", \"linear\" or \"smooth\"");
    m.interpolation = *parsed;
  }
}

void read(const Fields& f, KeyDelete& m) { m.index = f.integer("index", 0, kMaxIndex); }

void read(const Fields& f, KeyMove& m) {
  m.index = f.integer("index", 0, kMaxIndex);
  m.time = f.number("time", 0, kMaxTime);
}

void read(const Fields& f, BakeKeys& m) {
  m.rate = f.optional_number("rate", 1, 1000).value_or(animator::kDefaultClipRate);
}

void read(const Fields& f, Record& m) { m.on = f.boolean("on"); }
void read(const Fields& f, Seek& m) { m.time = f.number("time", -kMaxTime, kMaxTime); }

void read(const Fields& f, SetLoop& m) {
  m.loop = f.boolean("loop");
  m.start = f.optional_number("start", 0, kMaxTime).value_or(0);
  m.end = f.optional_number("end", -kMaxTime, kMaxTime).value_or(-1);
}

void read(const Fields& f, SetSpeed& m) { m.speed = f.number("speed", -100, 100); }

void read(const Fields& f, Layer& m) {
  m.index = f.integer("index", 0, kMaxIndex);
  if (f.has("remove")) {
    if (!f.boolean("remove")) f.fail("remove", "must be true when present");
    m.remove = true;
  } else if (f.has("muted")) {
    m.muted = f.boolean("muted");
  } else if (f.has("weight")) {
    m.weight = f.number("weight", -10, 10);
  } else {
    f.fail("muted", "one of muted, weight or remove is required");
  }
}

void read(const Fields& f, SetFalloff& m) { m.seconds = f.number("seconds", 0, 3600); }

// messages without fields: nothing to read
template <class M>
requires(M::kFields.empty()) void read(const Fields&, M&) {}

// the ClientMessage alternative whose kType is `type`, read from `f`; nullopt when none is
template <std::size_t... I>
std::optional<ClientMessage> read_message(std::string_view type,
                                          const Fields& f,
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
  const auto type_it = j.find("type");
  const Fields envelope(j, "message");
  if (type_it == j.end() || !type_it->is_string()) {
    throw ProtocolError("message.type: is required and must be a string", envelope.id());
  }
  if (j.contains("id") && !(j["id"].is_number() || j["id"].is_string() || j["id"].is_null())) {
    throw ProtocolError("message.id: must be a number or a string");
  }
  const std::string& type = type_it->get_ref<const std::string&>();
  const Fields fields(j, type);
  std::optional<ClientMessage> message =
      read_message(type, fields, std::make_index_sequence<std::variant_size_v<ClientMessage>>{});
  if (!message) {
    throw ProtocolError("type: unknown message type \"" + type.substr(0, 64) + "\"", envelope.id());
  }
  return ClientRequest{std::move(*message), envelope.id()};
}

}  // namespace server
