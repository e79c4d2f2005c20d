// Tests for server/messages.hpp and parse_client_message (server/protocol.hpp), no sockets:
// every client message type round-trips text -> struct -> JSON -> struct, malformed fields are
// refused naming "<type>.<field>", and the page (web/js/protocol.js) and docs/protocol.md know the
// same message types and fields as the structs.
#include "server/protocol.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "server/messages.hpp"
#include "tests/fixtures/fixtures.hpp"

// readable failures: messages print as their JSON
namespace server {
void PrintTo(const ClientRequest& r, std::ostream* os) { *os << to_json(r).dump(); }
template <class M>
requires requires { M::kType; }
void PrintTo(const M& m, std::ostream* os) { *os << to_json(ClientMessage(m)).dump(); }
}  // namespace server

namespace {

using nlohmann::json;
using server::ClientRequest;
using server::parse_client_message;

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in) << "cannot read " << path;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Text frames covering every message type, each optional field present and absent.
const std::vector<std::string>& sample_frames() {
  static const std::vector<std::string> frames = {
      R"({"type": "hello", "protocol": 1})",
      R"({"type": "drag_begin", "link": "r_hand", "target": [0.1, 1.2, -0.3], "id": 4})",
      R"({"type": "drag_begin", "link": "r_hand", "target": [0, 1, 0], "point": [0, 0, 0.05]})",
      R"({"type": "drag_move", "seq": 4294967295, "target": [0.25, 1, 1e-3], "id": "m1"})",
      R"({"type": "drag_move", "seq": 7, "target": [0, 1, 0], "rotation": [2, 0, 0, 0]})",
      R"({"type": "drag_end", "id": 5})",
      R"({"type": "pin", "link": "l_foot"})",
      R"({"type": "pin", "link": "l_foot", "mode": "pose", "point": [0, -0.04, 0.1]})",
      R"({"type": "unpin", "link": "l_foot"})",
      R"({"type": "move_pin", "link": "l_foot", "target": [0, 0.1, 0]})",
      R"({"type": "move_pin", "link": "l_foot", "target": [0, 0.1, 0], )"
      R"("rotation": [0.7, 0.7, 0, 0]})",
      R"({"type": "set_settings", "settings": {"iterations": 3, "gains": {"pin": 0.5}}})",
      R"({"type": "set_effects", "scene": {"gravity": true, "hard_limits": false}})",
      R"({"type": "key_insert"})",
      R"({"type": "key_insert", "time": 0.5, "interpolation": "step"})",
      R"({"type": "key_delete", "index": 2})",
      R"({"type": "key_move", "index": 0, "time": 1.25})",
      R"({"type": "bake_keys"})",
      R"({"type": "bake_keys", "rate": 24})",
      R"({"type": "record", "on": true})",
      R"({"type": "play"})",
      R"({"type": "pause"})",
      R"({"type": "seek", "time": -0.5})",
      R"({"type": "set_loop", "loop": false})",
      R"({"type": "set_loop", "loop": true, "start": 0.5, "end": 2})",
      R"({"type": "set_speed", "speed": -2})",
      R"({"type": "layer", "index": 1, "muted": true})",
      R"({"type": "layer", "index": 1, "weight": 0.25})",
      R"({"type": "layer", "index": 0, "remove": true})",
      R"({"type": "bake_layers"})",
      R"({"type": "set_falloff", "seconds": 0.75})",
      R"({"type": "undo", "id": 9})",
      R"({"type": "redo"})",
  };
  return frames;
}

TEST(Protocol, EveryMessageTypeRoundTripsThroughJson) {
  std::map<std::string, std::set<std::string>> fields_written;
  for (const std::string& text : sample_frames()) {
    SCOPED_TRACE(text);
    const ClientRequest parsed = parse_client_message(text);
    const json written = to_json(parsed);
    EXPECT_EQ(written.at("type"), server::message_type(parsed.message));
    EXPECT_EQ(parse_client_message(written.dump()), parsed) << written.dump();
    // the id comes back as sent
    const json sent = json::parse(text);
    EXPECT_EQ(parsed.id, sent.contains("id") ? sent["id"] : json(nullptr));
    auto& fields = fields_written[written.at("type").get<std::string>()];
    for (const auto& [key, value] : written.items()) {
      if (key != "type" && key != "id") fields.insert(key);
    }
  }
  // every type was sampled, and its fields, together, are exactly those its struct declares
  std::map<std::string, std::set<std::string>> declared;
  for (const server::MessageFields& m : server::client_message_fields()) {
    declared[m.type] = std::set<std::string>(m.fields.begin(), m.fields.end());
  }
  EXPECT_EQ(fields_written, declared);
}

TEST(Protocol, ValuesBuiltInCodeRoundTripThroughText) {
  const std::vector<ClientRequest> requests = {
      {server::Pin{.link = "l_foot", .mode = ik::TaskMode::kOrientation, .point = {0, 0.01, 0}}, 3},
      {server::DragMove{
           .seq = 12, .target = {0.1, 0.2, 0.3}, .rotation = server::Rotation{1, 0, 0, 0}},
       "drag-12"},
      {server::KeyInsert{.time = std::nullopt, .interpolation = animator::Interpolation::kLinear},
       nullptr},
      {server::SetEffects{.scene = {.gravity = true, .self_collision = true}}, 1},
      {server::Layer{.index = 2, .weight = 0.5}, nullptr},
      {server::SetLoop{.loop = false, .start = 1, .end = -1}, 2.5},
  };
  for (const ClientRequest& r : requests) {
    const std::string text = to_json(r).dump();
    EXPECT_EQ(parse_client_message(text), r) << text;
  }
  // a rotation stays as sent (normalized only when applied); extra keys are ignored
  const auto move =
      parse_client_message(R"({"type": "move_pin", "link": "x", "target": [0, 0, 0], )"
                           R"("rotation": [0, 0, 3, 0], "why": 1})");
  EXPECT_EQ(std::get<server::MovePin>(move.message).rotation, (server::Rotation{0, 0, 3, 0}));
  // defaults of absent fields
  EXPECT_EQ(std::get<server::Pin>(parse_client_message(R"({"type": "pin", "link": "a"})").message),
            (server::Pin{.link = "a", .mode = ik::TaskMode::kPosition, .point = {0, 0, 0}}));
  EXPECT_EQ(
      std::get<server::BakeKeys>(parse_client_message(R"({"type": "bake_keys"})").message).rate,
      animator::kDefaultClipRate);
}

// The message of the ProtocolError that parsing `text` throws ("" when it parses).
std::string refusal(const std::string& text, json* id = nullptr) {
  try {
    parse_client_message(text);
  } catch (const server::ProtocolError& e) {
    if (id) *id = e.id;
    return e.what();
  }
  return "";
}

TEST(Protocol, MalformedFieldsAreRefusedNamingTypeAndField) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"type": "hello", "protocol": "1"})", "hello.protocol: expected an integer, got string"},
      {R"({"type": "drag_begin", "link": 5, "target": [0, 0, 0]})",
       "drag_begin.link: expected a string, got number"},
      {R"({"type": "drag_begin", "link": "r_hand"})",
       "drag_begin.target: missing (rule: required)"},
      {R"({"type": "drag_begin", "link": "r_hand", "target": [0, 0, 0], "point": [0, 0]})",
       "drag_begin.point: expected an array of 3 numbers, got an array of 2 values"},
      {R"({"type": "drag_move", "seq": -1, "target": [0, 0, 0]})",
       "drag_move.seq: -1 is out of range (rule: an integer in [0, 4294967295])"},
      {R"({"type": "drag_move", "seq": 4294967296, "target": [0, 0, 0]})",
       "drag_move.seq: 4294967296 is out of range (rule: an integer in [0, 4294967295])"},
      {R"({"type": "drag_move", "seq": 1, "target": [0, "x", 0]})",
       "drag_move.target.1: expected a number, got string"},
      {R"({"type": "drag_move", "seq": 1, "target": [0, 0, 0], "rotation": [0, 0, 0, 0]})",
       "drag_move.rotation: quaternion norm is 0 (rule: a quaternion [w, x, y, z] of nonzero "
       "length)"},
      {R"({"type": "pin", "link": "l_foot", "mode": "glue"})",
       "pin.mode: expected \"position\", \"orientation\" or \"pose\""},
      {R"({"type": "pin", "link": "l_foot", "point": [1e5, 0, 0]})",
       "pin.point.0: 100000 is out of range (rule: a number in [-10000, 10000])"},
      {R"({"type": "unpin"})", "unpin.link: missing (rule: required)"},
      {R"({"type": "move_pin", "link": "l_foot", "target": [0, 0, 0], "rotation": [1, 0, 0]})",
       "move_pin.rotation: expected an array of 4 numbers, got an array of 3 values"},
      {R"({"type": "move_pin", "target": [0, 0, 0]})", "move_pin.link: missing (rule: required)"},
      {R"({"type": "set_settings", "settings": 3})",
       "set_settings.settings: expected an object, got number"},
      {R"({"type": "set_effects", "scene": {"wind": true}})",
       "set_effects.scene.wind: unknown key (rule: one of gravity, ground_contact, friction, "
       "hard_limits, self_collision, dynamic_pins)"},
      {R"({"type": "set_effects", "scene": {"gravity": 1}})",
       "set_effects.scene.gravity: expected true or false, got number"},
      {R"({"type": "key_insert", "time": -1})",
       "key_insert.time: -1 is out of range (rule: a number in [0, 1000000])"},
      {R"({"type": "key_insert", "interpolation": "cubic"})",
       "key_insert.interpolation: expected \"step\", \"linear\" or \"smooth\""},
      {R"({"type": "key_delete", "index": 1.5})",
       "key_delete.index: expected an integer, got a number with a fraction or an exponent"},
      {R"({"type": "key_move", "index": 0})", "key_move.time: missing (rule: required)"},
      {R"({"type": "bake_keys", "rate": 0})",
       "bake_keys.rate: 0 is out of range (rule: a number in [1, 1000])"},
      {R"({"type": "record", "on": "yes"})", "record.on: expected true or false, got string"},
      {R"({"type": "seek", "time": "soon"})", "seek.time: expected a number, got string"},
      {R"({"type": "set_loop", "start": 1})", "set_loop.loop: missing (rule: required)"},
      {R"({"type": "set_loop", "loop": true, "start": -1})", "set_loop.start"},
      {R"({"type": "set_speed", "speed": 1000})",
       "set_speed.speed: 1000 is out of range (rule: a number in [-100, 100])"},
      {R"({"type": "layer", "index": 0})",
       "layer.muted: one of muted, weight or remove is required"},
      {R"({"type": "layer", "index": 0, "remove": false})",
       "layer.remove: expected true when present"},
      {R"({"type": "layer", "index": -1, "muted": true})",
       "layer.index: -1 is out of range (rule: an integer in [0, 2147483647])"},
      {R"({"type": "set_falloff", "seconds": -1})", "set_falloff.seconds"},
  };
  std::set<std::string> types_refused;
  for (const auto& [text, expected] : cases) {
    json id;
    const std::string message = refusal(R"({"id": 17, )" + text.substr(1), &id);
    EXPECT_EQ(message.rfind(expected, 0), 0u) << text << " -> " << message;
    EXPECT_EQ(id, 17) << text;
    types_refused.insert(expected.substr(0, expected.find('.')));
  }
  // every message type that has fields has a malformed case
  std::set<std::string> with_fields;
  for (const server::MessageFields& m : server::client_message_fields()) {
    if (!m.fields.empty()) with_fields.insert(m.type);
  }
  EXPECT_EQ(types_refused, with_fields);
}

TEST(Protocol, MalformedEnvelopesAreRefused) {
  EXPECT_EQ(refusal("{"), "message: not valid JSON");
  EXPECT_EQ(refusal("[]").rfind("message: must be a JSON object", 0), 0u);
  EXPECT_EQ(refusal(R"({"type": 7})").rfind("message.type: is required", 0), 0u);
  EXPECT_EQ(refusal(R"({"id": {"a": 1}, "type": "play"})").rfind("message.id:", 0), 0u);
  json id;
  EXPECT_EQ(refusal(R"({"type": "teleport", "id": "t"})", &id),
            "type: unknown message type \"teleport\"");
  EXPECT_EQ(id, "t");
  // an unusable id is left out of the error rather than echoed
  EXPECT_NE(refusal(R"({"type": "seek", "id": [1], "time": "x"})", &id), "");
  EXPECT_TRUE(id.is_null());
}

// CLIENT_MESSAGES of web/js/protocol.js, read from the source text (the table is written as JSON).
nlohmann::ordered_json web_client_messages() {
  const std::string source = read_text(fixtures::source_dir() + "/web/js/protocol.js");
  const std::string head = "export const CLIENT_MESSAGES = ";
  const size_t start = source.find(head);
  if (start == std::string::npos) return nullptr;
  const size_t end = source.find("\n};", start);
  if (end == std::string::npos) return nullptr;
  return nlohmann::ordered_json::parse(
      source.substr(start + head.size(), end + 2 - start - head.size()), nullptr,
      /*allow_exceptions=*/false);
}

TEST(Protocol, ThePageKnowsTheSameMessagesAndFields) {
  const nlohmann::ordered_json web = web_client_messages();
  ASSERT_TRUE(web.is_object()) << "no JSON CLIENT_MESSAGES table in web/js/protocol.js";
  nlohmann::ordered_json ours = nlohmann::ordered_json::object();
  for (const server::MessageFields& m : server::client_message_fields()) ours[m.type] = m.fields;
  // same types, same fields, same order (both follow docs/protocol.md; ordered_json compares in
  // order)
  EXPECT_EQ(web, ours);
}

TEST(Protocol, TheDocsListEveryMessageType) {
  const std::string doc = read_text(fixtures::source_dir() + "/docs/protocol.md");
  const size_t start = doc.find("### Client → server");
  const size_t end = doc.find("### Server → client");
  ASSERT_NE(start, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  // the first column of the table: "| `play` / `pause` | ..."
  std::set<std::string> documented;
  std::istringstream rows(doc.substr(start, end - start));
  const std::regex name("`([a-z_]+)`");
  for (std::string row; std::getline(rows, row);) {
    if (row.rfind("| `", 0) != 0) continue;
    const std::string first = row.substr(0, row.find('|', 1));
    for (auto it = std::sregex_iterator(first.begin(), first.end(), name);
         it != std::sregex_iterator(); ++it) {
      documented.insert((*it)[1]);
    }
  }
  std::set<std::string> types;
  for (const server::MessageFields& m : server::client_message_fields()) types.insert(m.type);
  EXPECT_EQ(documented, types);
}

}  // namespace
