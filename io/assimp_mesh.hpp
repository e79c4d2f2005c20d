// The mesh stage of the skinned import (io/assimp_import.hpp), run in the child: the skinned
// triangle meshes of the file merged into one core::SkinnedMesh in the bind pose, in our world
// (metres, Y up). Up to four influences per vertex, the largest kept and renormalized; a vertex
// without any follows the root; a mesh without bones that a node carries follows that node's
// link whole. Each source mesh is a part with its material's base colour and
// base-colour (else diffuse) texture, with its first set of texture coordinates. Internal to io/.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "io/assimp_scene.hpp"
#include "io/assimp_skeleton.hpp"

namespace io::assimp_detail {

/// The bytes of an image file a material names (as written in the file: relative to the file's
/// folder, or a path from another machine); empty when it cannot be read.
using ImageFileReader = std::function<std::string(const std::string& name)>;

/// The skinned mesh; its bones are the links that carry weights (model_link maps links to link
/// indices of the model), each with the inverse of its bind pose.
/// Requires: mesh_bind_spaces, bind_poses and place_carried_meshes on `skinned` and `skeleton`.
/// @throws std::runtime_error for more than INT_MAX vertices
SkinnedMesh build_mesh(const aiScene& scene,
                       const SceneNodes& scene_nodes,
                       const SkinnedMeshes& skinned,
                       const WorldAxes& world,
                       const Skeleton& skeleton,
                       const std::vector<int>& model_link,
                       const ImageFileReader& read_image_file,
                       Warnings& warnings);

}  // namespace io::assimp_detail
