#include "io/assimp_rigid.hpp"

#include <stdexcept>
#include <string>

namespace io::assimp_detail {

SkinnedMeshes collect_moved_nodes(const aiScene& scene,
                                  const SceneNodes& nodes,
                                  Warnings& warnings) {
  SkinnedMeshes out;
  std::vector<char> moved(nodes.nodes.size(), 0);
  for (unsigned a = 0; a < scene.mNumAnimations; ++a) {
    const aiAnimation* anim = scene.mAnimations[a];
    if (anim == nullptr) continue;
    for (unsigned c = 0; c < anim->mNumChannels; ++c) {
      const aiNodeAnim* channel = anim->mChannels[c];
      if (channel == nullptr) continue;
      const bool has_keys =
          channel->mNumPositionKeys + channel->mNumRotationKeys + channel->mNumScalingKeys > 0;
      const auto it = nodes.by_name.find(channel->mNodeName.C_Str());
      if (has_keys && it != nodes.by_name.end()) moved[it->second] = 1;
    }
  }
  for (int n = 0; n < static_cast<int>(nodes.nodes.size()); ++n) {
    if (moved[n]) out.moved_nodes.push_back(n);
  }
  if (out.moved_nodes.empty()) {
    throw std::runtime_error(
        "it has no skinned mesh (no mesh with bones) and no animation that moves its nodes, so "
        "there is no skeleton to import");
  }
  for (int n = 0; n < static_cast<int>(nodes.nodes.size()); ++n) {
    const aiNode* ai = nodes.nodes[n].ai;
    for (unsigned k = 0; k < ai->mNumMeshes; ++k) {
      if (ai->mMeshes[k] >= scene.mNumMeshes) continue;
      const aiMesh* mesh = scene.mMeshes[ai->mMeshes[k]];
      if (mesh == nullptr || (mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      SourceMesh sm;
      sm.mesh = mesh;
      sm.rigid_node = n;
      out.meshes.push_back(sm);
    }
  }
  warnings.add("no mesh has bones: the " + std::to_string(out.moved_nodes.size()) +
               " nodes its animations move are imported as links" +
               (out.meshes.empty() ? std::string(" (it has no mesh)")
                                   : ", and each of its " + std::to_string(out.meshes.size()) +
                                         " meshes moves rigidly with the link of the node that "
                                         "carries it"));
  return out;
}

}  // namespace io::assimp_detail
