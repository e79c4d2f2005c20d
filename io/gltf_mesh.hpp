// The geometry the glTF writer (io/gltf.hpp) puts in its buffer, independent of how the
// document is encoded: the checks on a skinned mesh, its unit normals and per-vertex influences,
// and the boxes of the stick figure. Internal to io/.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "io/core_names.hpp"

namespace io::gltf_detail {

/// True for a finite rotation matrix: orthonormal to 1e-6, determinant > 0.
bool is_rotation(const Matrix3& R);

/// Checks that `skin` fits `model`: one normal (or none), joint and weight entry per vertex;
/// bones that are distinct links with finite rigid inverse binds; finite positions and normals;
/// non-negative weights with a positive sum on bones of the mesh; triangles on its vertices;
/// texture coordinates, parts and textures as core::check_mesh_materials says.
/// @throws std::invalid_argument "glTF export: skinned mesh: ..." naming the vertex, bone or
///         triangle
void check_skin(const Model& model, const SkinnedMesh& skin);

/// Unit normals: the given ones, else area-weighted face normals; +Y where neither is defined.
std::vector<Eigen::Vector3f> unit_normals(const SkinnedMesh& skin);

/// Four (joint, weight) pairs of one vertex, joints as skin joints: duplicates merged,
/// normalized so the float weights sum to 1 as closely as float allows (the residual goes to
/// the largest weight), unused slots (0, 0).
/// @param skin_joint_of_bone  skin joint (node) index of each bone of the mesh
void normalized_influences(const std::array<int, 4>& joints,
                           const std::array<float, 4>& weights,
                           const std::vector<int>& skin_joint_of_bone,
                           std::uint16_t* j_out,
                           float* w_out);

/// Vertex attributes and triangle indices of a mesh as the buffer stores them.
struct MeshArrays {
  std::vector<float> pos, nrm;     // 3 per vertex
  std::vector<std::uint16_t> jnt;  // 4 per vertex
  std::vector<std::uint32_t> idx;  // 3 per triangle
};

/// One box from a to b with half width r (a == b: a cube of half size r at a), its vertices
/// placed by X and skinned rigidly to skin joint `joint`; flat faces, four vertices each.
void append_stick_box(
    const Transform& X, const Vector3& a, const Vector3& b, double r, int joint, MeshArrays& out);

/// The stick figure of link i (a cube of half size 1.5 r on its origin, a box of half width r to
/// each child's origin) placed by X_bind, its link's bind pose, and skinned to skin joint i - 1.
void append_link_sticks(
    const Model& model, int i, const Transform& X_bind, double r, MeshArrays& out);

/// WEIGHTS_0 of a rigidly skinned mesh: (1, 0, 0, 0) for every vertex.
std::vector<float> rigid_weights(const MeshArrays& m);

}  // namespace io::gltf_detail
