// The skinned mesh of a session as one binary download for the page (GET
// /api/sessions/{id}/mesh; docs/protocol.md): "PDMS", a little-endian uint32 header length, the
// header (JSON, padded with spaces to 4 bytes), then the arrays, each 4-byte aligned:
//   positions  float32 × 3 per vertex (bind pose, world frame)
//   normals    float32 × 3 per vertex (absent when the header says "normals": false)
//   indices    uint32 × 3 per triangle
//   joints     uint16 × 4 per vertex (indices into the header's "bones"), padded to 4 bytes
//   weights    float32 × 4 per vertex
//   uvs        float32 × 2 per vertex (absent unless the header says "uvs": true; origin at the
//              image's bottom-left corner)
//   textures   each texture's image file (PNG or JPEG), in the header's order
// The header: {"name", "vertices", "triangles", "normals": bool, "bones": [link index of each skin
// joint in the snapshot's character.links], "inverse_bind": [[16 numbers, column-major] per
// bone], "base_color": [r, g, b, a], "uvs": bool, "parts": [{"first", "count" (triangles),
// "base_color", "texture": index or -1}], "textures": [{"mime_type", "bytes"}]}. Without "parts"
// the mesh is one part of "base_color" (meshes saved before parts existed read so).
#pragma once

#include <string>

#include "core/skin.hpp"

namespace server {

/// The bytes of `mesh` in the format above.
std::string encode_mesh_binary(const core::SkinnedMesh& mesh);

/// The mesh back from those bytes (a session keeps its mesh in <id>.mesh in this format), bound
/// to a character of `nlinks` links (the world included). Every count, index and number is
/// checked before use.
/// @throws std::runtime_error naming `source`, the field and the rule broken
core::SkinnedMesh decode_mesh_binary(const std::string& bytes,
                                     int nlinks,
                                     const std::string& source);

}  // namespace server
