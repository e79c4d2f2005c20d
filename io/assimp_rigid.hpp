// A file without skinned meshes whose animations move its nodes: an animation-only export (a
// skeleton without its mesh, as "without skin" downloads come) or a rigid mechanism (parts that
// turn and slide). The nodes the animations move become the links, in their rest pose, and
// every triangle mesh a node carries follows its link whole. Internal to io/, a stage of the
// skinned import (io/assimp_import.hpp) run in the child.
#pragma once

#include "io/assimp_scene.hpp"

namespace io::assimp_detail {

/// The nodes the animations of `scene` move (SkinnedMeshes::moved_nodes) and every triangle mesh
/// a node carries (SourceMesh::rigid_node), one entry per node that carries it. Adds a warning
/// saying what was imported so.
/// @throws std::runtime_error when no animation moves a node: then the file has no skeleton
SkinnedMeshes collect_moved_nodes(const aiScene& scene,
                                  const SceneNodes& nodes,
                                  Warnings& warnings);

}  // namespace io::assimp_detail
