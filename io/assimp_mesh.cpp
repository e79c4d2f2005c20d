#include "io/assimp_mesh.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

#include "io/assimp_rigid.hpp"

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

// every vertex of a mesh a node carries: weight 1 on the link of that node, or of the nearest
// node above it that is a link
void append_rigid_influences(const SourceMesh& sm,
                             const SceneNodes& scene,
                             const Skeleton& s,
                             BoneTable& bones,
                             SkinnedMesh& out) {
  const int bone = bones.bone(carrying_link(sm, scene, s));
  out.joints.insert(out.joints.end(), sm.mesh->mNumVertices, {bone, 0, 0, 0});
  out.weights.insert(out.weights.end(), sm.mesh->mNumVertices, {1.0f, 0.0f, 0.0f, 0.0f});
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

// the base (else diffuse) colour of a material, clamped to [0, 1]; nullopt when it has neither
std::optional<Eigen::Vector4f> material_color(const aiMaterial& mat) {
  aiColor4D c;
  if (mat.Get(AI_MATKEY_BASE_COLOR, c) != aiReturn_SUCCESS &&
      mat.Get(AI_MATKEY_COLOR_DIFFUSE, c) != aiReturn_SUCCESS) {
    return std::nullopt;
  }
  const Eigen::Vector4f col(c.r, c.g, c.b, c.a);
  if (!col.allFinite()) return std::nullopt;
  return col.cwiseMax(0.0f).cwiseMin(1.0f);
}

// The textures of the materials, each image read once: embedded ones as the file holds them,
// others from beside the file. An image that is neither PNG nor JPEG, or cannot be found, leaves
// its material in its base colour (a warning).
class TextureTable {
 public:
  TextureTable(const aiScene& scene,
               SkinnedMesh& out,
               const ImageFileReader& read_image_file,
               Warnings& warnings)
      : scene_(scene), out_(out), read_image_file_(read_image_file), warnings_(warnings) {}

  // the texture index of the material's base-colour (else diffuse) image, or -1
  int texture_of(const aiMaterial& mat) {
    aiString name;
    if (mat.GetTexture(aiTextureType_BASE_COLOR, 0, &name) != aiReturn_SUCCESS &&
        mat.GetTexture(aiTextureType_DIFFUSE, 0, &name) != aiReturn_SUCCESS) {
      return -1;
    }
    const std::string key = name.C_Str();
    if (const auto found = index_.find(key); found != index_.end()) return found->second;
    const int index = load(key);
    index_[key] = index;
    return index;
  }

 private:
  int load(const std::string& name) {
    std::string bytes;
    if (const aiTexture* embedded = scene_.GetEmbeddedTexture(name.c_str())) {
      if (embedded->mHeight != 0) {
        warnings_.add("texture '" + name +
                      "' is stored as raw texels, which are not read: drawn in its base colour");
        return -1;
      }
      bytes.assign(reinterpret_cast<const char*>(embedded->pcData), embedded->mWidth);
    } else {
      bytes = read_image_file_(name);
      if (bytes.empty()) {
        warnings_.add("texture '" + name +
                      "' is not in the file nor beside it: drawn in its base colour");
        return -1;
      }
    }
    const std::string mime = core::image_mime_type(bytes);
    if (mime.empty()) {
      warnings_.add("texture '" + name + "' is not a PNG or JPEG image: drawn in its base colour");
      return -1;
    }
    out_.textures.push_back(core::MeshTexture{mime, std::move(bytes)});
    return static_cast<int>(out_.textures.size()) - 1;
  }

  const aiScene& scene_;
  SkinnedMesh& out_;
  const ImageFileReader& read_image_file_;
  Warnings& warnings_;
  std::map<std::string, int> index_;
};

// the first set of texture coordinates of one mesh ((0, 0) where it has none)
void append_uvs(const aiMesh& mesh, SkinnedMesh& out) {
  const aiVector3D* uv = mesh.mTextureCoords[0];
  for (std::size_t v = 0; v < mesh.mNumVertices; ++v) {
    Eigen::Vector2f t(0.0f, 0.0f);
    if (uv != nullptr) t = Eigen::Vector2f(uv[v].x, uv[v].y);
    out.uvs.push_back(t.allFinite() ? t : Eigen::Vector2f(0.0f, 0.0f));
  }
}

// the part of the triangles from `first` on: its material's colour and texture
core::MeshPart mesh_part(const aiScene& scene,
                         const aiMesh& mesh,
                         std::size_t first,
                         const SkinnedMesh& out,
                         TextureTable& textures) {
  core::MeshPart part;
  part.first_triangle = static_cast<int>(first);
  part.triangle_count = static_cast<int>(out.triangles.size() - first);
  if (mesh.mMaterialIndex < scene.mNumMaterials) {
    const aiMaterial& mat = *scene.mMaterials[mesh.mMaterialIndex];
    if (const auto color = material_color(mat)) part.base_color = *color;
    part.texture = textures.texture_of(mat);
  }
  return part;
}

}  // namespace

SkinnedMesh build_mesh(const aiScene& scene,
                       const SceneNodes& scene_nodes,
                       const SkinnedMeshes& skinned,
                       const WorldAxes& world,
                       const Skeleton& skeleton,
                       const std::vector<int>& model_link,
                       const ImageFileReader& read_image_file,
                       Warnings& warnings) {
  SkinnedMesh out;
  BoneTable bones(out, skeleton, model_link);
  TextureTable textures(scene, out, read_image_file, warnings);
  std::size_t unweighted = 0;
  for (const SourceMesh& sm : skinned.meshes) {
    const aiMesh* mesh = sm.mesh;
    const std::size_t base = out.positions.size();
    if (base + mesh->mNumVertices > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
      throw std::runtime_error("too many vertices");
    }
    if (out.name.empty()) out.name = mesh->mName.C_Str();
    append_vertices(*mesh, world.A * sm.B, out);
    append_uvs(*mesh, out);
    if (sm.carrier_node >= 0) {
      append_rigid_influences(sm, scene_nodes, skeleton, bones, out);
    } else {
      unweighted += append_influences(sm, skeleton, bones, out);
    }
    const std::size_t first_triangle = out.triangles.size();
    append_triangles(*mesh, base, out);
    out.parts.push_back(mesh_part(scene, *mesh, first_triangle, out, textures));
  }
  if (!out.parts.empty()) out.base_color = out.parts.front().base_color;
  // a mesh none of whose parts is textured needs no texture coordinates
  const bool textured = std::any_of(out.parts.begin(), out.parts.end(),
                                    [](const core::MeshPart& p) { return p.texture >= 0; });
  if (!textured) out.uvs.clear();
  if (unweighted > 0) {
    warnings.add(std::to_string(unweighted) +
                 " vertices have no bone weights; they follow the root '" + skeleton.link_name[0] +
                 "'");
  }
  return out;
}

}  // namespace io::assimp_detail
