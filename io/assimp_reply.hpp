// The bytes the import child (io/assimp_child.hpp) sends its parent through the sandbox pipe
// (io/sandbox.hpp), and their decoding in the parent, which treats them as untrusted input:
// every read is bounds-checked, every count capped by the bytes that remain, every string by a
// size cap, and the result validated (rigid inverse binds, weights summing to 1, bones that are
// links, clips that fit the model) before anything else sees it. Internal to io/.
//
// Layout: the signature "PDSKIN01", a status byte, then for an error one string (the message),
// for success: the model as character JSON (io/character_json.hpp); the mesh (name, vertices as
// position, normal, 4 joints, 4 weights; triangles; bones as link index and inverse bind
// R row-major, p; base colour); the clips (name, start time, frame time, frames of nq doubles);
// the unit scale; the dropped offset per model link; the warnings. Scalars are little-endian
// (the child and the parent are the same program), strings are a u32 length and bytes, arrays a
// u32 count and elements.
#pragma once

#include <string>

#include "io/assimp_import.hpp"

namespace io::assimp_detail {

/// The reply for a finished import (`result.model` must be set).
std::string encode_reply(const SkinnedImport& result);

/// The reply for an import that failed with `message`.
std::string encode_error_reply(const std::string& message);

/// The import that `reply` carries, validated; its warnings are the child's, then the model
/// loader's.
/// @throws ModelError "<path>: <message>" for an error reply, or when the model's JSON is
///         rejected; std::runtime_error saying what is malformed otherwise
SkinnedImport decode_reply(const std::string& path, const std::string& reply);

}  // namespace io::assimp_detail
