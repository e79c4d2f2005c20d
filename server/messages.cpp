#include "server/messages.hpp"

#include <utility>

#include "animator/session_file.hpp"

namespace server {
namespace {

using nlohmann::json;

// the fields of each message; `type` is added by to_json(ClientMessage)
json fields_of(const Hello& m) { return {{"protocol", m.protocol}}; }

json fields_of(const DragBegin& m) {
  return {{"link", m.link}, {"target", m.target}, {"point", m.point}};
}

json fields_of(const DragMove& m) {
  json j{{"seq", m.seq}, {"target", m.target}};
  if (m.rotation) j["rotation"] = *m.rotation;
  return j;
}

json fields_of(const Pin& m) {
  return {{"link", m.link}, {"mode", ik::to_string(m.mode)}, {"point", m.point}};
}

json fields_of(const Unpin& m) { return {{"link", m.link}}; }

json fields_of(const MovePin& m) {
  json j{{"link", m.link}, {"target", m.target}};
  if (m.rotation) j["rotation"] = *m.rotation;
  return j;
}

json fields_of(const SetSettings& m) { return {{"settings", m.settings}}; }

json fields_of(const SetEffects& m) { return {{"scene", animator::scene_to_json(m.scene)}}; }

json fields_of(const KeyInsert& m) {
  json j{{"interpolation", animator::to_string(m.interpolation)}};
  if (m.time) j["time"] = *m.time;
  return j;
}

json fields_of(const KeyDelete& m) { return {{"index", m.index}}; }
json fields_of(const KeyMove& m) { return {{"index", m.index}, {"time", m.time}}; }
json fields_of(const BakeKeys& m) { return {{"rate", m.rate}}; }
json fields_of(const Record& m) { return {{"on", m.on}}; }
json fields_of(const Seek& m) { return {{"time", m.time}}; }

json fields_of(const SetLoop& m) { return {{"loop", m.loop}, {"start", m.start}, {"end", m.end}}; }

json fields_of(const SetSpeed& m) { return {{"speed", m.speed}}; }

json fields_of(const Layer& m) {
  json j{{"index", m.index}};
  if (m.remove) j["remove"] = true;
  if (m.muted) j["muted"] = *m.muted;
  if (m.weight) j["weight"] = *m.weight;
  return j;
}

json fields_of(const SetFalloff& m) { return {{"seconds", m.seconds}}; }

// messages without fields
template <class M>
requires(M::kFields.empty()) json fields_of(const M&) { return json::object(); }

template <std::size_t... I>
std::vector<MessageFields> fields_table(std::index_sequence<I...>) {
  auto row = [](auto type_tag) {
    using M = typename decltype(type_tag)::type;
    return MessageFields{M::kType, std::vector<std::string>(M::kFields.begin(), M::kFields.end())};
  };
  return {row(std::type_identity<std::variant_alternative_t<I, ClientMessage>>{})...};
}

}  // namespace

const char* message_type(const ClientMessage& message) {
  return std::visit([](const auto& m) { return std::decay_t<decltype(m)>::kType; }, message);
}

std::vector<MessageFields> client_message_fields() {
  return fields_table(std::make_index_sequence<std::variant_size_v<ClientMessage>>{});
}

json to_json(const ClientMessage& message) {
  return std::visit(
      [](const auto& m) {
        json j = fields_of(m);
        j["type"] = std::decay_t<decltype(m)>::kType;
        return j;
      },
      message);
}

json to_json(const ClientRequest& request) {
  json j = to_json(request.message);
  if (!request.id.is_null()) j["id"] = request.id;
  return j;
}

}  // namespace server
