// The first stage of the skinned import (io/assimp_import.hpp), run in the child: assimp's scene
// read into plain tables. Its nodes (depth-first, with rest transforms), the world convention
// (metres, Y up) and the skinned triangle meshes with the nodes of their bones. Also the matrix
// helpers and the warning list that the later stages (assimp_skeleton, assimp_animation,
// assimp_mesh) share. Internal to io/.
#pragma once

#include <assimp/scene.h>

#include <Eigen/Core>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

#include "io/core_names.hpp"

namespace io::assimp_detail {

using Matrix4 = Eigen::Matrix4d;

/// A node scale this far from 1 (after the unit scale) cannot be carried by a rigid link: the
/// bind pose or a clip that has one gets a warning.
constexpr double kScaleTolerance = 1e-3;

/// aiMatrix4x4 (row-major, translation in the last column) as an Eigen matrix.
Matrix4 to_eigen(const aiMatrix4x4& m);
/// T · R · S as an affine matrix.
Matrix4 trs(const Vector3& t, const Quaternion& r, const Vector3& s);
/// The rigid part of an affine matrix: the rotation nearest its linear part (polar
/// decomposition) and its translation. `scale_error` gets max |σ − 1| over the singular values.
Transform rigid(const Matrix4& M, double& scale_error);
/// True when every entry is finite.
bool finite_matrix(const aiMatrix4x4& m);
/// A number with three significant digits, for messages.
std::string num(double v);

/// What the import approximated or left out, in the order found; each entry names the file.
class Warnings {
 public:
  explicit Warnings(std::string source) : source_(std::move(source)) {}
  void add(const std::string& what) { list_.push_back(source_ + ": " + what); }
  std::vector<std::string>& list() { return list_; }

 private:
  std::string source_;  // file name, without its folder
  std::vector<std::string> list_;
};

/// A node of the file, with its rest (bind-time) transform.
struct Node {
  const aiNode* ai = nullptr;
  int parent = -1;
  int depth = 0;
  std::string name;
  Matrix4 local_rest = Matrix4::Identity();   // mTransformation
  Matrix4 global_rest = Matrix4::Identity();  // product from the scene root
  Vector3 rest_t = Vector3::Zero();           // mTransformation decomposed
  Quaternion rest_r = Quaternion::Identity();
  Vector3 rest_s = Vector3::Ones();
};

/// Every node of the scene in depth-first order, so parents come before their children.
struct SceneNodes {
  std::vector<Node> nodes;
  std::unordered_map<std::string, int> by_name;  // the first node of a name, as assimp's FindNode
};

/// @throws std::runtime_error for more than 4 · kMaxLinks nodes or a non-finite node transform
SceneNodes index_nodes(const aiScene& scene);

/// Metres and Y up: A = [s C, 0; 0, 1] applied to every world matrix of the file. glTF is both
/// already; FBX lengths are scaled by UnitScaleFactor / 100 and its axes turned by the file's
/// axis system (a warning when that is not a rotation).
struct WorldAxes {
  double unit_scale = 1;               // metres per file unit (s)
  Matrix3 axes = Matrix3::Identity();  // rows: our x, y, z as file axes (C)
  Matrix4 A = Matrix4::Identity();
};

/// @param ext  the file's extension, lower case (".fbx" reads the FBX metadata)
WorldAxes world_axes(const aiScene& scene, const std::string& ext, Warnings& warnings);

/// A triangle mesh of the file: skinned by its bones, or without bones and carried whole by a node
/// (io/assimp_rigid.hpp).
struct SourceMesh {
  const aiMesh* mesh = nullptr;
  std::vector<int> bone_node;  // node of each aiBone, or -1
  // a mesh without bones: the node that carries it (its vertices are in that node's frame); it
  // follows the link of that node, or of the nearest node above it that is a link
  int carrier_node = -1;
  // bind space → file world (set by mesh_bind_spaces, for a carried mesh by place_carried_meshes)
  Matrix4 B = Matrix4::Identity();
};

/// The meshes and what becomes a link: the skinned triangle meshes and the offset matrix of every
/// bone node or, in a file without skinned meshes, the nodes its animations move; and the meshes
/// without bones that nodes carry (io/assimp_rigid.hpp).
struct SkinnedMeshes {
  std::vector<SourceMesh> meshes;
  std::map<int, Matrix4> offset;   // bone node → offset matrix (first mesh naming it)
  std::map<int, int> offset_mesh;  // bone node → that mesh
  // without skinned meshes: the nodes an animation moves, each a link whose bind pose is its
  // rest pose (io/assimp_rigid.hpp)
  std::vector<int> moved_nodes;
};

/// Bones of every skinned triangle mesh; a bone without a node loses its weights (a warning).
/// Empty (no offset) when no mesh has bones with nodes.
/// @throws std::runtime_error for a non-finite offset matrix
SkinnedMeshes collect_bones(const aiScene& scene, const SceneNodes& nodes, Warnings& warnings);

/// The offset matrix of `node` among the bones of `mesh`, or the identity.
Matrix4 offset_for(const SourceMesh& mesh, int node);

/// B of every mesh: the rest pose of its top bone times that bone's offset matrix, so that every
/// bone's global transform times its offset matrix is B in the bind pose (a mesh carried by a
/// node: place_carried_meshes, io/assimp_rigid.hpp).
void mesh_bind_spaces(const SceneNodes& nodes, SkinnedMeshes& skinned);

}  // namespace io::assimp_detail
