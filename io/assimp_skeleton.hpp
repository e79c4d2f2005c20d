// The skeleton stage of the skinned import (io/assimp_import.hpp), run in the child: which nodes
// become links, their bind pose, and the core::Model built from them. The root is the deepest
// node above every bone; the links are the nodes on the paths from it to the bones. In a file
// without skinned meshes the nodes its animations move stand for the bones (their bind pose is
// their rest pose), and the root is also above every node that carries a mesh. The root
// gets a free joint placed at its bind pose in the world, every other link a spherical joint (or
// a free one when a clip moves it, see assimp_animation.hpp) placed at its bind pose relative
// to its parent, so the neutral configuration is the bind pose. Internal to io/.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/assimp_import.hpp"
#include "io/assimp_scene.hpp"

namespace io::assimp_detail {

/// The links, parents first, and their bind pose.
struct Skeleton {
  int root = 0;                        // node of link 0
  std::vector<int> links;              // node of each link, in depth-first node order
  std::vector<int> link_of_node;       // per node, or -1
  std::vector<int> parent_link;        // per link, -1 for the root
  std::vector<std::string> link_name;  // unique and non-empty
  // set by bind_poses
  std::vector<Matrix4> bind_global;  // file world, per link
  std::vector<Transform> bind;       // our world (A · bind_global), rigid, per link
};

/// The root, the links and their names (renamed links get a warning).
/// @throws std::runtime_error for more than kMaxLinks links
Skeleton choose_links(const SceneNodes& nodes, const SkinnedMeshes& skinned, Warnings& warnings);

/// Bind pose of every link: B_m · O⁻¹ for a bone with offset matrix O in mesh m, the rest pose
/// for the root without one, and the rest placement below its parent link for a node between
/// bones. A scale in it is dropped, with a warning.
/// Requires: mesh_bind_spaces(nodes, skinned).
/// @throws std::runtime_error for a singular offset matrix
void bind_poses(const SceneNodes& nodes,
                const SkinnedMeshes& skinned,
                const WorldAxes& world,
                Skeleton& skeleton,
                Warnings& warnings);

/// The model: joints from the bind pose (`is_free` per link: free, else spherical), masses from
/// bone lengths (a slender cylinder per bone, radius a tenth of its length, sharing
/// options.total_mass). Its link names are skeleton.link_name.
/// @param name  the model's name (the file's stem)
std::shared_ptr<const Model> build_model(const SceneNodes& nodes,
                                         const WorldAxes& world,
                                         const Skeleton& skeleton,
                                         const std::vector<char>& is_free,
                                         const ImportOptions& options,
                                         const std::string& name);

}  // namespace io::assimp_detail
