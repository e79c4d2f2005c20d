#include "io/assimp_mesh.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace io::assimp_detail {

namespace {

// the mesh's bones, added the first time a link carries a weight
class BoneTable {
 public:
  BoneTable(SkinnedMesh& out, const Skeleton& s, const std::vector<int>& model_link)
      : out_(out), s_(s), model_link_(model_link), bone_of_link_(s.links.size(), -1) {}

  // the bone index of a link
  int bone(int link) {
    if (bone_of_link_[link] < 0) {
      bone_of_link_[link] = static_cast<int>(out_.bones.size());
      out_.bones.push_back(model_link_[link]);
      out_.inverse_bind.push_back(s_.bind[link].inverse());
    }
    return bone_of_link_[link];
  }

 private:
  SkinnedMesh& out_;
  const Skeleton& s_;
  const std::vector<int>& model_link_;
  std::vector<int> bone_of_link_;
};

// positions and normals of one mesh, taken from bind space to our world by M
void append_vertices(const aiMesh& mesh, const Matrix4& M, SkinnedMesh& out) {
  const Matrix3 N = M.topLeftCorner<3, 3>().inverse().transpose();
  for (std::size_t v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& p = mesh.mVertices[v];
    const Eigen::Vector4d pw = M * Eigen::Vector4d(p.x, p.y, p.z, 1);
    out.positions.push_back(pw.head<3>().cast<float>());
    if (mesh.mNormals != nullptr) {
      const aiVector3D& n = mesh.mNormals[v];
      Vector3 nw = N * Vector3(n.x, n.y, n.z);
      if (nw.norm() > 0) nw.normalize();
      out.normals.push_back(nw.cast<float>());
    } else {
      out.normals.emplace_back(0.0f, 0.0f, 0.0f);  // the exporter computes face normals
    }
  }
}

// joints and weights of one mesh's vertices: up to four influences, the largest kept and
// normalized; a vertex without any follows the root. Returns how many had none.
std::size_t append_influences(const SourceMesh& sm,
                              const Skeleton& s,
                              BoneTable& bones,
                              SkinnedMesh& out) {
  const aiMesh* mesh = sm.mesh;
  const std::size_t nv = mesh->mNumVertices;
  std::vector<std::vector<std::pair<float, int>>> infl(nv);
  for (unsigned b = 0; b < mesh->mNumBones; ++b) {
    const int node = sm.bone_node[b];
    if (node < 0) continue;
    const int link = s.link_of_node[node];
    const aiBone* ab = mesh->mBones[b];
    for (unsigned k = 0; k < ab->mNumWeights; ++k) {
      const aiVertexWeight& vw = ab->mWeights[k];
      if (vw.mVertexId >= nv || !(vw.mWeight > 0) || !std::isfinite(vw.mWeight)) continue;
      infl[vw.mVertexId].push_back({vw.mWeight, bones.bone(link)});
    }
  }
  std::size_t unweighted = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    auto& iv = infl[v];
    std::sort(iv.begin(), iv.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    std::array<int, 4> j{0, 0, 0, 0};
    std::array<float, 4> w{0, 0, 0, 0};
    if (iv.empty()) {
      ++unweighted;
      j[0] = bones.bone(0);
      w[0] = 1;
    }
    float sum = 0;
    for (std::size_t k = 0; k < iv.size() && k < 4; ++k) sum += iv[k].first;
    for (std::size_t k = 0; k < iv.size() && k < 4; ++k) {
      j[k] = iv[k].second;
      w[k] = iv[k].first / sum;
    }
    out.joints.push_back(j);
    out.weights.push_back(w);
  }
  return unweighted;
}

// the mesh's triangles, vertex indices offset by `base`; a face with an index out of range is
// left out
void append_triangles(const aiMesh& mesh, std::size_t base, SkinnedMesh& out) {
  const std::size_t nv = mesh.mNumVertices;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;
    std::array<int, 3> t{};
    bool ok = true;
    for (int c = 0; c < 3; ++c) {
      ok = ok && face.mIndices[c] < nv;
      t[c] = static_cast<int>(base + (ok ? face.mIndices[c] : 0));
    }
    if (ok) out.triangles.push_back(t);
  }
}

// the base (else diffuse) colour of the mesh's material into `out`, clamped to [0, 1]; false
// when the material has neither
bool material_color(const aiScene& scene, const aiMesh& mesh, SkinnedMesh& out) {
  if (mesh.mMaterialIndex >= scene.mNumMaterials) return false;
  const aiMaterial* mat = scene.mMaterials[mesh.mMaterialIndex];
  aiColor4D c;
  if (mat->Get(AI_MATKEY_BASE_COLOR, c) != aiReturn_SUCCESS &&
      mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) != aiReturn_SUCCESS) {
    return false;
  }
  const Eigen::Vector4f col(c.r, c.g, c.b, c.a);
  if (col.allFinite()) out.base_color = col.cwiseMax(0.0f).cwiseMin(1.0f);
  return true;
}

}  // namespace

SkinnedMesh build_mesh(const aiScene& scene,
                       const SkinnedMeshes& skinned,
                       const WorldAxes& world,
                       const Skeleton& skeleton,
                       const std::vector<int>& model_link,
                       Warnings& warnings) {
  SkinnedMesh out;
  BoneTable bones(out, skeleton, model_link);
  std::size_t unweighted = 0;
  bool colored = false;
  for (const SourceMesh& sm : skinned.meshes) {
    const aiMesh* mesh = sm.mesh;
    const std::size_t base = out.positions.size();
    if (base + mesh->mNumVertices > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
      throw std::runtime_error("too many vertices");
    }
    if (out.name.empty()) out.name = mesh->mName.C_Str();
    append_vertices(*mesh, world.A * sm.B, out);
    unweighted += append_influences(sm, skeleton, bones, out);
    append_triangles(*mesh, base, out);
    if (!colored) colored = material_color(scene, *mesh, out);
  }
  if (unweighted > 0) {
    warnings.add(std::to_string(unweighted) +
                 " vertices have no bone weights; they follow the root '" + skeleton.link_name[0] +
                 "'");
  }
  return out;
}

}  // namespace io::assimp_detail
