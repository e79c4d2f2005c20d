// A skinned mesh bound to a character's links (linear blend skinning), as imported from glTF,
// FBX or DAE and exported to glTF.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/spatial.hpp"

namespace core {

/// An image a material is painted with, as its file holds it (PNG or JPEG bytes).
struct MeshTexture {
  std::string mime_type;  // "image/png" or "image/jpeg"
  std::string bytes;
};

/// A run of triangles drawn with one material.
struct MeshPart {
  int first_triangle = 0;
  int triangle_count = 0;
  Eigen::Vector4f base_color = Eigen::Vector4f(0.8f, 0.8f, 0.8f, 1.0f);  // times the texture
  int texture = -1;  // index into SkinnedMesh::textures, or -1
};

struct SkinnedMesh {
  std::string name;
  std::vector<Eigen::Vector3f> positions;     // bind pose, world frame of the model
  std::vector<Eigen::Vector3f> normals;       // empty or one per position
  std::vector<std::array<int, 3>> triangles;  // indices into positions
  std::vector<std::array<int, 4>> joints;     // per vertex: indices into `bones`
  std::vector<std::array<float, 4>> weights;  // per vertex, summing to 1
  std::vector<int> bones;                     // link index of each skin joint
  std::vector<Transform> inverse_bind;        // per bone: world → bone frame at bind pose
  Eigen::Vector4f base_color = Eigen::Vector4f(0.8f, 0.8f, 0.8f, 1.0f);  // the first part's
  /// Texture coordinates, empty or one per position: origin at the image's bottom-left corner
  /// (OpenGL's convention; glTF's v runs the other way).
  std::vector<Eigen::Vector2f> uvs;
  /// Consecutive runs covering every triangle in order; empty: one part of base_color.
  std::vector<MeshPart> parts;
  std::vector<MeshTexture> textures;

  bool empty() const { return positions.empty(); }
};

/// "image/png" or "image/jpeg" from the first bytes of an image file; empty for anything else.
std::string image_mime_type(const std::string& bytes);

/// Empty when the mesh's texture coordinates, parts and textures fit it: one finite uv per
/// vertex (or none); parts that cover every triangle in order, each with a finite colour in
/// [0, 1] and a texture that exists (or -1); textures that are PNG or JPEG images as their
/// mime type says. Otherwise the first rule broken, naming the part, texture or vertex.
std::string check_mesh_materials(const SkinnedMesh& mesh);

/// The mesh's vertices in the world with its links at X_W (world pose per link, as forward
/// kinematics gives them): linear blend skinning, p = Σ_k w_k · X_W[bone_k] · inverse_bind_k ·
/// p_bind with the weights normalized to sum 1. X_skin receives each bone's bind → posed transform
/// (X_W[bone] · inverse_bind), which the caller may reuse (normals).
std::vector<Vector3> skinned_positions(const SkinnedMesh& skin,
                                       const std::vector<Transform>& X_W,
                                       std::vector<Transform>& X_skin);

}  // namespace core
