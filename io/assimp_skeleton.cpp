#include "io/assimp_skeleton.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "core/model_builder.hpp"

namespace io::assimp_detail {

namespace {

// the deepest node above every node of `under` (not empty): their lowest common ancestor
int common_root(const std::vector<Node>& nodes, const std::vector<int>& under) {
  int root = under.front();
  for (int node : under) {
    int a = root, b = node;
    while (nodes[a].depth > nodes[b].depth) a = nodes[a].parent;
    while (nodes[b].depth > nodes[a].depth) b = nodes[b].parent;
    while (a != b) {
      a = nodes[a].parent;
      b = nodes[b].parent;
    }
    root = a;
  }
  return root;
}

// unique, non-empty link names: the node's name, "node<N>" for an unnamed one, "_2", "_3", ...
// appended to repeats
void name_links(const std::vector<Node>& nodes, Skeleton& s, Warnings& warnings) {
  std::unordered_map<std::string, int> used;
  for (int n : s.links) {
    std::string name = nodes[n].name.empty() ? "node" + std::to_string(n) : nodes[n].name;
    std::string unique = name;
    for (int k = 2; used.count(unique) != 0; ++k) unique = name + "_" + std::to_string(k);
    used.emplace(unique, n);
    s.link_name.push_back(unique);
    if (unique != nodes[n].name) {
      warnings.add("node '" + nodes[n].name + "' is imported as link '" + unique +
                   "' (names must be unique and non-empty)");
    }
  }
}

}  // namespace

Skeleton choose_links(const SceneNodes& scene, const SkinnedMeshes& skinned, Warnings& warnings) {
  const std::vector<Node>& nodes = scene.nodes;
  Skeleton s;
  // the bones, or the nodes the animations move; the root is also above every mesh a node carries
  std::vector<int> bones = skinned.moved_nodes;
  for (const auto& [node, unused] : skinned.offset) {
    (void)unused;
    bones.push_back(node);
  }
  if (bones.empty()) throw std::logic_error("choose_links: no bone and no moved node");
  std::vector<int> under = bones;
  for (const SourceMesh& sm : skinned.meshes) {
    if (sm.carrier_node >= 0) under.push_back(sm.carrier_node);
  }
  s.root = common_root(nodes, under);
  std::vector<char> is_link(nodes.size(), 0);
  for (int node : bones) {
    for (int n = node; n != s.root && !is_link[n]; n = nodes[n].parent) is_link[n] = 1;
  }
  is_link[s.root] = 1;
  // links in depth-first node order: parents first
  for (int n = 0; n < static_cast<int>(nodes.size()); ++n) {
    if (is_link[n]) s.links.push_back(n);
  }
  if (s.links.size() > static_cast<std::size_t>(core::kMaxLinks)) {
    throw std::runtime_error("the skeleton has " + std::to_string(s.links.size()) +
                             " bones (rule: at most " + std::to_string(core::kMaxLinks) + ")");
  }
  s.link_of_node.assign(nodes.size(), -1);
  for (std::size_t k = 0; k < s.links.size(); ++k) {
    s.link_of_node[s.links[k]] = static_cast<int>(k);
  }
  s.parent_link.assign(s.links.size(), -1);
  for (std::size_t k = 1; k < s.links.size(); ++k) {
    s.parent_link[k] = s.link_of_node[nodes[s.links[k]].parent];
  }
  name_links(nodes, s, warnings);
  return s;
}

void bind_poses(const SceneNodes& scene,
                const SkinnedMeshes& skinned,
                const WorldAxes& world,
                Skeleton& s,
                Warnings& warnings) {
  const std::vector<Node>& nodes = scene.nodes;
  s.bind_global.assign(s.links.size(), Matrix4::Identity());
  for (std::size_t k = 0; k < s.links.size(); ++k) {
    const int n = s.links[k];
    const auto it = skinned.offset.find(n);
    if (it != skinned.offset.end()) {
      const Matrix4 O = it->second;
      if (std::abs(O.topLeftCorner<3, 3>().determinant()) < 1e-12) {
        throw std::runtime_error("bone '" + nodes[n].name + "' has a singular offset matrix");
      }
      s.bind_global[k] = skinned.meshes[skinned.offset_mesh.at(n)].B * O.inverse();
    } else if (k == 0) {
      s.bind_global[k] = nodes[n].global_rest;
    } else {
      // a node between bones: its rest placement below its parent link's bind pose
      const int p = s.links[s.parent_link[k]];
      s.bind_global[k] =
          s.bind_global[s.parent_link[k]] * nodes[p].global_rest.inverse() * nodes[n].global_rest;
    }
  }
  s.bind.resize(s.links.size());
  double worst = 0;
  int worst_link = 0;
  for (std::size_t k = 0; k < s.links.size(); ++k) {
    double e = 0;
    s.bind[k] = rigid(world.A * s.bind_global[k], e);
    if (e > worst) {
      worst = e;
      worst_link = static_cast<int>(k);
    }
  }
  if (worst > kScaleTolerance) {
    warnings.add("bind pose of '" + s.link_name[worst_link] +
                 "' is scaled (largest |scale - 1| = " + num(worst) +
                 " after the unit scale); links are rigid, the scale is dropped");
  }
}

namespace {

// per link: the bone's length and its mean direction (link frame) toward its ends
struct Bones {
  std::vector<Vector3> toward;  // mean child offset, link frame
  std::vector<double> length;   // metres, at least min_length
};

// bone length: to the children (links, else end nodes such as Blender's "_end"), else half the
// parent's along the parent's direction
Bones bone_lengths(const SceneNodes& scene, const WorldAxes& world, const Skeleton& s) {
  const std::size_t nl = s.links.size();
  const std::vector<Transform>& bind = s.bind;
  Bones out{std::vector<Vector3>(nl, Vector3::Zero()), std::vector<double>(nl, 0)};
  std::vector<Vector3>& toward = out.toward;
  std::vector<double>& length = out.length;
  for (std::size_t k = 0; k < nl; ++k) {
    std::vector<Vector3> ends;
    for (std::size_t c = k + 1; c < nl; ++c) {
      if (s.parent_link[c] == static_cast<int>(k)) ends.push_back(bind[k].inverse_apply(bind[c].p));
    }
    if (ends.empty()) {
      const Node& node = scene.nodes[s.links[k]];
      for (unsigned c = 0; c < node.ai->mNumChildren; ++c) {
        const aiNode* child = node.ai->mChildren[c];
        if (child->mNumMeshes > 0) continue;
        const Matrix4 G = world.A * s.bind_global[k] * to_eigen(child->mTransformation);
        ends.push_back(bind[k].inverse_apply(G.topRightCorner<3, 1>()));
      }
    }
    for (const Vector3& e : ends) {
      toward[k] += e / static_cast<double>(ends.size());
      length[k] += e.norm() / static_cast<double>(ends.size());
    }
  }
  double extent = 0;
  for (std::size_t k = 0; k < nl; ++k) extent = std::max(extent, (bind[k].p - bind[0].p).norm());
  const double min_length = std::max(1e-3 * extent, 1e-4);
  for (std::size_t k = 0; k < nl; ++k) {
    if (length[k] < min_length && k > 0) {
      length[k] = 0.5 * length[s.parent_link[k]];
      // continue the parent's direction
      toward[k] = bind[k].R.transpose() * (bind[k].p - bind[s.parent_link[k]].p);
      if (toward[k].norm() > 0) toward[k] = toward[k].normalized() * length[k];
    }
    length[k] = std::max(length[k], min_length);
  }
  return out;
}

}  // namespace

std::shared_ptr<const Model> build_model(const SceneNodes& scene,
                                         const WorldAxes& world,
                                         const Skeleton& s,
                                         const std::vector<char>& is_free,
                                         const ImportOptions& options,
                                         const std::string& name) {
  const std::size_t nl = s.links.size();
  const Bones bones = bone_lengths(scene, world, s);
  double total_length = 0;
  for (double l : bones.length) total_length += l;

  ModelBuilder b(name);
  for (std::size_t k = 0; k < nl; ++k) {
    core::LinkSpec l;
    l.name = s.link_name[k];
    l.parent = k == 0 ? "" : s.link_name[s.parent_link[k]];
    l.joint.type = is_free[k] ? core::JointType::kFree : core::JointType::kSpherical;
    l.joint.X_PJ = k == 0 ? s.bind[0] : s.bind[s.parent_link[k]].inverse() * s.bind[k];
    // the builder wants an orthonormal rotation to 1e-6; re-orthonormalize the product
    l.joint.X_PJ.R = Quaternion(l.joint.X_PJ.R).normalized().toRotationMatrix();
    // a slender solid cylinder along the bone, radius a tenth of its length
    const Vector3& toward = bones.toward[k];
    const double length = bones.length[k];
    const double m = options.total_mass * length / total_length;
    const double r = 0.1 * length;
    const Vector3 axis = toward.norm() > 0 ? Vector3(toward.normalized()) : Vector3::UnitY();
    l.mass = m;
    l.com = toward.norm() > 0 ? Vector3(0.5 * toward) : Vector3::Zero();
    const Matrix3 aa = axis * axis.transpose();
    l.I_com = m * (3 * r * r + length * length) / 12.0 * (Matrix3::Identity() - aa) +
              0.5 * m * r * r * aa;
    b.add_link(std::move(l));
  }
  return b.finalize();
}

}  // namespace io::assimp_detail
