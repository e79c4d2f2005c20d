// Meshes without bones, carried whole by a node. In a file without skinned meshes whose
// animations move its nodes (an animation-only export, a skeleton without its mesh as "without
// skin" downloads come, or a rigid mechanism of parts that turn and slide) the nodes the
// animations move become the links, in their rest pose, and every triangle mesh a node carries
// follows its link. In a skinned file, a mesh without bones carried by a node of the skeleton (a
// prop in a hand, eyes under the head) follows its link too. Internal to io/, stages of the
// skinned import (io/assimp_import.hpp) run in the child.
#pragma once

#include "io/assimp_scene.hpp"
#include "io/assimp_skeleton.hpp"

namespace io::assimp_detail {

/// The nodes the animations of `scene` move (SkinnedMeshes::moved_nodes) and every triangle mesh
/// without bones a node carries (SourceMesh::carrier_node), one entry per node that carries it.
/// Adds a warning saying what was imported so.
/// @throws std::runtime_error when no animation moves a node: then the file has no skeleton
SkinnedMeshes collect_moved_nodes(const aiScene& scene,
                                  const SceneNodes& nodes,
                                  Warnings& warnings);

/// In a skinned file: adds to `skinned` every triangle mesh without bones carried by a link's
/// node or a node below one; the others are left out. Each gets a warning.
void add_carried_meshes(const aiScene& scene,
                        const SceneNodes& nodes,
                        const Skeleton& skeleton,
                        SkinnedMeshes& skinned,
                        Warnings& warnings);

/// The link a carried mesh follows: that of its node, else of the nearest node above it that is
/// a link. Requires: a link at or above sm.carrier_node.
int carrying_link(const SourceMesh& sm, const SceneNodes& nodes, const Skeleton& skeleton);

/// B of every carried mesh: its node's rest pose carried by its link from rest to bind,
/// bind(L) · rest(L)⁻¹ · rest(N), so it sits on its link in the bind pose as it does at rest.
/// Requires: bind_poses(nodes, skinned, world, skeleton, warnings).
void place_carried_meshes(const SceneNodes& nodes,
                          const Skeleton& skeleton,
                          SkinnedMeshes& skinned);

}  // namespace io::assimp_detail
