// The child's side of the skinned import (io/assimp_import.hpp): assimp reads the file, and the
// converter stages turn its scene into our import, in order: nodes, world convention and bones
// (assimp_scene), links and bind pose (assimp_skeleton), motion sampling (assimp_animation), the
// model (assimp_skeleton), the mesh (assimp_mesh) and the clips (assimp_animation). Runs only
// inside run_sandboxed (io/sandbox.hpp). Internal to io/.
#pragma once

#include <string>

#include "io/assimp_import.hpp"

struct aiScene;

namespace io::assimp_detail {

/// The extension of `path` in lower case (".glb"), which names the file's format.
std::string lower_extension(const std::string& path);

/// assimp's scene → our model, skinned mesh and clips, with the warnings of every stage.
/// @param path  the imported file (its name prefixes warnings, its stem names the model)
/// @throws std::runtime_error saying what in the scene cannot be imported
SkinnedImport convert_scene(const aiScene& scene,
                            const std::string& path,
                            const ImportOptions& options);

/// The child's work: reads `path` with assimp (opening only files in its folder), converts the
/// scene and writes the reply (io/assimp_reply.hpp) to fd, an error reply when either step
/// fails. std::bad_alloc, assimp's included, propagates (the sandbox reports the memory limit).
/// @return 0, or 1 when the reply could not be written
int import_in_child(const std::string& path, const ImportOptions& options, int fd);

}  // namespace io::assimp_detail
