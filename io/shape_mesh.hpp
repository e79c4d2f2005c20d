// Triangle meshes of primitive shapes (capsules, spheres, cylinders, boxes) with outward normals
// and a colour per vertex, appended to one indexed mesh: the figure of a thumbnail
// (server/thumbnail_scene.hpp) and the shape mesh of a glTF export (io/gltf.hpp).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/model.hpp"
#include "core/spatial.hpp"

namespace io {

/// Interleaved vertices (position, normal, linear RGB colour: 9 floats) and triangle indices.
struct TriangleMesh {
  static constexpr int kFloatsPerVertex = 9;
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;

  std::size_t vertex_count() const { return vertices.size() / kFloatsPerVertex; }
  /// Index of the new vertex.
  std::uint32_t add_vertex(const Eigen::Vector3f& p,
                           const Eigen::Vector3f& n,
                           const Eigen::Vector3f& colour);
  void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c);
};

/// Tessellation of the round shapes: segments around the axis, rings per hemisphere.
constexpr int kRoundSegments = 24;
constexpr int kHemisphereRings = 8;

/// A capsule along the z axis of frame S: end-sphere centres at z = ±length / 2.
/// X_FS places S in the mesh frame F. length 0 gives a sphere.
void append_capsule(TriangleMesh& mesh,
                    const core::Transform& X_FS,
                    double radius,
                    double length,
                    const Eigen::Vector3f& colour);
void append_sphere(TriangleMesh& mesh,
                   const core::Vector3& p_F,
                   double radius,
                   const Eigen::Vector3f& colour);
/// A closed cylinder along the z axis of S, of full height `length`.
void append_cylinder(TriangleMesh& mesh,
                     const core::Transform& X_FS,
                     double radius,
                     double length,
                     const Eigen::Vector3f& colour);
/// A box centred on S with full extents `size`.
void append_box(TriangleMesh& mesh,
                const core::Transform& X_FS,
                const core::Vector3& size,
                const Eigen::Vector3f& colour);
/// A capsule from a to b (both in F).
void append_segment(TriangleMesh& mesh,
                    const core::Vector3& a_F,
                    const core::Vector3& b_F,
                    double radius,
                    const Eigen::Vector3f& colour);

/// The shapes drawn for link `link`: its visual shapes when one of them is a primitive, else its
/// collision shapes when one of them is, else nullptr (mesh shapes are never tessellated).
const std::vector<core::Geometry>* primitive_shapes(const core::Model& model, int link);

/// A primitive shape of a link (X_FS = pose of the shape frame). Returns false, appending
/// nothing, for a mesh shape.
bool append_geometry(TriangleMesh& mesh,
                     const core::Transform& X_FS,
                     const core::Geometry& g,
                     const Eigen::Vector3f& colour);

}  // namespace io
