#include "core/skin.hpp"

namespace core {

std::string image_mime_type(const std::string& bytes) {
  if (bytes.rfind("\x89PNG\r\n\x1a\n", 0) == 0) return "image/png";
  if (bytes.rfind("\xff\xd8\xff", 0) == 0) return "image/jpeg";
  return {};
}

std::string check_mesh_materials(const SkinnedMesh& mesh) {
  const std::size_t n = mesh.positions.size();
  if (!mesh.uvs.empty() && mesh.uvs.size() != n) {
    return std::to_string(mesh.uvs.size()) + " texture coordinates for " + std::to_string(n) +
           " vertices (rule: one per vertex or none)";
  }
  for (std::size_t v = 0; v < mesh.uvs.size(); ++v) {
    if (!mesh.uvs[v].allFinite()) {
      return "vertex " + std::to_string(v) + ": texture coordinate is not finite";
    }
  }
  for (std::size_t t = 0; t < mesh.textures.size(); ++t) {
    const MeshTexture& tex = mesh.textures[t];
    const std::string kind = image_mime_type(tex.bytes);
    if (kind.empty() || kind != tex.mime_type) {
      return "texture " + std::to_string(t) + ": declared '" + tex.mime_type + "' but holds " +
             (kind.empty() ? std::string("no PNG or JPEG image") : kind) +
             " (rule: a PNG or JPEG image of the declared type)";
    }
  }
  std::size_t next = 0;  // the first triangle the parts have not covered yet
  for (std::size_t k = 0; k < mesh.parts.size(); ++k) {
    const MeshPart& part = mesh.parts[k];
    const std::string at = "part " + std::to_string(k) + ": ";
    if (part.first_triangle < 0 || static_cast<std::size_t>(part.first_triangle) != next ||
        part.triangle_count < 0) {
      return at + "starts at triangle " + std::to_string(part.first_triangle) + " with " +
             std::to_string(part.triangle_count) + " triangles (rule: parts cover the triangles " +
             "in order, the next one starts at " + std::to_string(next) + ")";
    }
    next += static_cast<std::size_t>(part.triangle_count);
    if (next > mesh.triangles.size()) {
      return at + "runs past the last triangle (" + std::to_string(mesh.triangles.size()) + ")";
    }
    if (!part.base_color.allFinite() || part.base_color.minCoeff() < 0 ||
        part.base_color.maxCoeff() > 1) {
      return at + "base colour is not finite in [0, 1]";
    }
    if (part.texture < -1 || part.texture >= static_cast<int>(mesh.textures.size())) {
      return at + "texture " + std::to_string(part.texture) + " does not exist (" +
             std::to_string(mesh.textures.size()) + " textures)";
    }
  }
  if (!mesh.parts.empty() && next != mesh.triangles.size()) {
    return "the parts cover " + std::to_string(next) + " of " +
           std::to_string(mesh.triangles.size()) + " triangles (rule: every triangle has a part)";
  }
  return {};
}

std::vector<Vector3> skinned_positions(const SkinnedMesh& skin,
                                       const std::vector<Transform>& X_W,
                                       std::vector<Transform>& X_skin) {
  X_skin.resize(skin.bones.size());
  for (std::size_t j = 0; j < skin.bones.size(); ++j)
    X_skin[j] = X_W[skin.bones[j]] * skin.inverse_bind[j];
  std::vector<Vector3> p_W(skin.positions.size());
  for (std::size_t v = 0; v < skin.positions.size(); ++v) {
    const Vector3 p_bind = skin.positions[v].cast<double>();
    const auto& w = skin.weights[v];
    const double total = double{w[0]} + w[1] + w[2] + w[3];
    Vector3 p = Vector3::Zero();
    for (int k = 0; k < 4; ++k) {
      if (w[k] != 0.0f) p += (w[k] / total) * (X_skin[skin.joints[v][k]] * p_bind);
    }
    p_W[v] = p;
  }
  return p_W;
}

}  // namespace core
