// The wire protocol v1 (docs/protocol.md): client messages parsed into the values of
// messages.hpp with errors that name the field and the rule, the snapshot and state JSON,
// `report`, `ack` and `error` messages, and the binary pose frame ("PDPF").
// Pure functions: no sockets, no threads.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "animator/session.hpp"
#include "core/model.hpp"
#include "ik/solver.hpp"
#include "server/messages.hpp"

namespace server {

constexpr int kProtocolVersion = 1;
constexpr std::uint32_t kPoseMagic = 0x46504450;  // "PDPF" little-endian
constexpr std::size_t kPoseHeaderBytes = 36;
constexpr std::size_t kPoseBytesPerLink = 44;
constexpr std::size_t kPoseSeqOffset = 12;
/// Caps of docs/protocol.md.
constexpr std::size_t kMaxUploadBytes = std::size_t{64} << 20;
constexpr std::size_t kMaxWsMessageBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxJsonBodyBytes = std::size_t{1} << 20;

/// A message the server refuses; what() names the field and the rule. `id` is the request's id
/// when it could be read (null otherwise).
class ProtocolError : public std::runtime_error {
 public:
  ProtocolError(const std::string& message, nlohmann::json request_id = nullptr)
      : std::runtime_error(message), id(std::move(request_id)) {}
  nlohmann::json id;
};

/// Reads one text frame into a message and its id; the fields are checked for type and range
/// (docs/protocol.md), link names only when the message is applied (apply_message.hpp).
/// @throws ProtocolError naming "<type>.<field>" and the rule
ClientRequest parse_client_message(std::string_view text);

/// The character as the snapshot lists it (docs/protocol.md "Snapshot").
nlohmann::json character_json(const core::Model& model, const std::string& name, bool skinned);
/// The snapshot without `type` and `character`: what the `state` message carries.
nlohmann::json state_json(const animator::Session& session, const std::string& session_id);
/// The full snapshot, with `character`; `type` is added by the WebSocket side.
nlohmann::json snapshot_json(const animator::Session& session, const std::string& session_id);

/// `report` of a solver step.
nlohmann::json report_json(const ik::Report& report);
std::string ack_message(const nlohmann::json& id, const std::string& request);
/// `code`, when not empty, tells kinds of error apart: kNotSaved.
std::string error_message(const nlohmann::json& id,
                          const std::string& message,
                          const std::string& code = "");
/// The `code` of an `error` on an edit the server could not save (and so took back).
constexpr const char* kNotSaved = "not_saved";

/// The `physics` object of a pose frame while physics runs (docs/protocol.md "Pose frames").
nlohmann::json physics_json(const animator::PhysicsMeasures& measures);

/// The binary pose frame of the session's current pose; while physics runs, followed by the
/// JSON object {"physics": ...}.
std::string encode_pose_frame(const animator::Session& session,
                              std::uint32_t frame_id,
                              std::uint32_t last_seq);
/// Rewrites the `last applied seq` field of an encoded frame (one frame, many connections).
void set_pose_frame_seq(std::string& frame, std::uint32_t last_seq);

}  // namespace server
