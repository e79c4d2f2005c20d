#include "io/gltf_shape_mesh.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/shape_mesh.hpp"

namespace io::gltf_detail {

namespace {

Eigen::Vector3f position(const TriangleMesh& mesh, std::uint32_t v) {
  return Eigen::Vector3f::Map(&mesh.vertices[v * TriangleMesh::kFloatsPerVertex]);
}

// a triangle of zero area (a capsule's pole, a sphere's doubled equator), which importers
// such as assimp turn into lines or points in a mesh of their own
bool degenerate(const TriangleMesh& mesh, const std::uint32_t* t) {
  const Eigen::Vector3f a = position(mesh, t[0]), b = position(mesh, t[1]),
                        c = position(mesh, t[2]);
  return a == b || b == c || a == c || (b - a).cross(c - a).squaredNorm() == 0.0f;
}

// appends the triangles of `mesh` that have an area and the vertices they use (position,
// normal; the colour is left out), every vertex skinned to `joint`
void append_rigid(const TriangleMesh& mesh, int joint, MeshArrays& out) {
  constexpr std::uint32_t kUnused = 0xffffffffu;
  std::vector<std::uint32_t> index_of(mesh.vertex_count(), kUnused);
  for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    if (degenerate(mesh, &mesh.indices[t])) continue;
    for (std::size_t k = t; k < t + 3; ++k) {
      const std::uint32_t v = mesh.indices[k];
      if (index_of[v] == kUnused) {
        index_of[v] = static_cast<std::uint32_t>(out.pos.size() / 3);
        const float* f = &mesh.vertices[v * TriangleMesh::kFloatsPerVertex];
        out.pos.insert(out.pos.end(), {f[0], f[1], f[2]});
        out.nrm.insert(out.nrm.end(), {f[3], f[4], f[5]});
        out.jnt.insert(out.jnt.end(), {static_cast<std::uint16_t>(joint), 0, 0, 0});
      }
      out.idx.push_back(index_of[v]);
    }
  }
}

// the tessellated primitive shapes of link i at its bind pose
TriangleMesh link_shapes(const Model& model, int i, const Transform& X_bind) {
  TriangleMesh mesh;
  for (const core::Geometry& g : *primitive_shapes(model, i)) {
    append_geometry(mesh, X_bind * g.X_LinkShape, g, Eigen::Vector3f::Ones());
  }
  for (float x : mesh.vertices) {
    if (!std::isfinite(x)) {
      throw std::invalid_argument("glTF export: link '" + model.link_name[i] +
                                  "': a shape gives a vertex that is not finite");
    }
  }
  return mesh;
}

}  // namespace

bool has_primitive_shapes(const Model& model) {
  for (int i = 1; i < model.njoints; ++i) {
    if (primitive_shapes(model, i) != nullptr) return true;
  }
  return false;
}

MeshArrays shape_mesh(const Model& model,
                      const std::vector<Transform>& X_bind,
                      double stick_radius) {
  MeshArrays out;
  for (int i = 1; i < model.njoints; ++i) {
    const std::size_t before = out.idx.size();
    if (primitive_shapes(model, i) != nullptr) {
      append_rigid(link_shapes(model, i, X_bind[i]), i - 1, out);
    }
    // no shape, or shapes without area
    if (out.idx.size() == before) append_link_sticks(model, i, X_bind[i], stick_radius, out);
  }
  return out;
}

}  // namespace io::gltf_detail
