#include "io/assimp_rigid.hpp"

#include <stdexcept>
#include <string>

namespace io::assimp_detail {

namespace {

// every triangle mesh without bones that a node carries, once per node that carries it
std::vector<SourceMesh> meshes_carried_by_nodes(const aiScene& scene, const SceneNodes& nodes) {
  std::vector<SourceMesh> out;
  for (int n = 0; n < static_cast<int>(nodes.nodes.size()); ++n) {
    const aiNode* ai = nodes.nodes[n].ai;
    for (unsigned k = 0; k < ai->mNumMeshes; ++k) {
      if (ai->mMeshes[k] >= scene.mNumMeshes) continue;
      const aiMesh* mesh = scene.mMeshes[ai->mMeshes[k]];
      if (mesh == nullptr || mesh->mNumBones > 0) continue;
      if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      SourceMesh sm;
      sm.mesh = mesh;
      sm.carrier_node = n;
      out.push_back(sm);
    }
  }
  return out;
}

// the nearest node at or above `node` that is a link, or -1
int link_at_or_above(int node, const SceneNodes& nodes, const Skeleton& skeleton) {
  while (node >= 0 && skeleton.link_of_node[node] < 0) node = nodes.nodes[node].parent;
  return node;
}

}  // namespace

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
  out.meshes = meshes_carried_by_nodes(scene, nodes);
  warnings.add("no mesh has bones: the " + std::to_string(out.moved_nodes.size()) +
               " nodes its animations move are imported as links" +
               (out.meshes.empty() ? std::string(" (it has no mesh)")
                                   : ", and each of its " + std::to_string(out.meshes.size()) +
                                         " meshes moves rigidly with the link of the node that "
                                         "carries it"));
  return out;
}

void add_carried_meshes(const aiScene& scene,
                        const SceneNodes& nodes,
                        const Skeleton& skeleton,
                        SkinnedMeshes& skinned,
                        Warnings& warnings) {
  int added = 0;
  for (const SourceMesh& sm : meshes_carried_by_nodes(scene, nodes)) {
    const std::string& node = nodes.nodes[sm.carrier_node].name;
    if (link_at_or_above(sm.carrier_node, nodes, skeleton) < 0) {
      warnings.add("mesh '" + std::string(sm.mesh->mName.C_Str()) +
                   "' has no bones and its node '" + node +
                   "' is not on the skeleton: it is left out");
      continue;
    }
    skinned.meshes.push_back(sm);
    ++added;
  }
  if (added == 1) {
    warnings.add("1 mesh without bones moves rigidly with the link of the node that carries it");
  } else if (added > 1) {
    warnings.add(std::to_string(added) +
                 " meshes without bones move rigidly with the links of the nodes that carry them");
  }
}

int carrying_link(const SourceMesh& sm, const SceneNodes& nodes, const Skeleton& skeleton) {
  const int node = link_at_or_above(sm.carrier_node, nodes, skeleton);
  if (node < 0) throw std::logic_error("carrying_link: a carried mesh is not on the skeleton");
  return skeleton.link_of_node[node];
}

void place_carried_meshes(const SceneNodes& nodes,
                          const Skeleton& skeleton,
                          SkinnedMeshes& skinned) {
  for (SourceMesh& sm : skinned.meshes) {
    if (sm.carrier_node < 0) continue;
    const int link = carrying_link(sm, nodes, skeleton);
    // rest(L)⁻¹ · rest(N) as the product of the local rest transforms below L down to N: no
    // inverse of rest(L), which a scale of zero at or above L would make unusable
    Matrix4 below_link = Matrix4::Identity();
    for (int n = sm.carrier_node; n != skeleton.links[link]; n = nodes.nodes[n].parent) {
      below_link = nodes.nodes[n].local_rest * below_link;
    }
    sm.B = skeleton.bind_global[link] * below_link;
  }
}

}  // namespace io::assimp_detail
