#include "io/shape_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace io {

std::uint32_t TriangleMesh::add_vertex(const Eigen::Vector3f& p,
                                       const Eigen::Vector3f& n,
                                       const Eigen::Vector3f& colour) {
  const auto index = static_cast<std::uint32_t>(vertex_count());
  vertices.insert(vertices.end(),
                  {p.x(), p.y(), p.z(), n.x(), n.y(), n.z(), colour.x(), colour.y(), colour.z()});
  return index;
}

void TriangleMesh::add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  indices.insert(indices.end(), {a, b, c});
}

namespace {

Eigen::Vector3f to_float(const core::Vector3& v) { return v.cast<float>(); }

// a grid of (rows + 1) × (kRoundSegments + 1) vertices starting at `first`, stitched into quads
void stitch_rings(TriangleMesh& mesh, std::uint32_t first, int rows) {
  const std::uint32_t stride = kRoundSegments + 1;
  for (int r = 0; r < rows; ++r) {
    for (int s = 0; s < kRoundSegments; ++s) {
      const std::uint32_t a = first + r * stride + s, b = a + 1, c = a + stride, d = c + 1;
      mesh.add_triangle(a, c, b);
      mesh.add_triangle(b, c, d);
    }
  }
}

// a flat disc at height z of S facing +z (up = true) or -z
void append_disc(TriangleMesh& mesh,
                 const core::Transform& X_FS,
                 double radius,
                 double z,
                 bool up,
                 const Eigen::Vector3f& colour) {
  const Eigen::Vector3f n = to_float(X_FS.R.col(2) * (up ? 1.0 : -1.0));
  const std::uint32_t centre = mesh.add_vertex(to_float(X_FS * core::Vector3(0, 0, z)), n, colour);
  for (int s = 0; s <= kRoundSegments; ++s) {
    const double a = 2 * std::numbers::pi * s / kRoundSegments;
    const core::Vector3 p_S(radius * std::cos(a), radius * std::sin(a), z);
    mesh.add_vertex(to_float(X_FS * p_S), n, colour);
  }
  for (int s = 0; s < kRoundSegments; ++s) {
    const std::uint32_t a = centre + 1 + s;
    if (up)
      mesh.add_triangle(centre, a, a + 1);
    else
      mesh.add_triangle(centre, a + 1, a);
  }
}

}  // namespace

void append_capsule(TriangleMesh& mesh,
                    const core::Transform& X_FS,
                    double radius,
                    double length,
                    const Eigen::Vector3f& colour) {
  // rings from the top pole to the bottom pole; the equator appears twice, at +length/2 (end of
  // the top hemisphere) and -length/2 (start of the bottom one), and the band between them is the
  // cylindrical part
  const std::uint32_t first = static_cast<std::uint32_t>(mesh.vertex_count());
  const int rings = 2 * kHemisphereRings + 1;
  for (int r = 0; r <= rings; ++r) {
    const bool top = r <= kHemisphereRings;
    const double polar =
        std::numbers::pi / 2 *
        (top ? static_cast<double>(r) / kHemisphereRings
             : 1.0 + static_cast<double>(r - kHemisphereRings - 1) / kHemisphereRings);
    const double z_offset = (top ? 0.5 : -0.5) * length;
    for (int s = 0; s <= kRoundSegments; ++s) {
      const double a = 2 * std::numbers::pi * s / kRoundSegments;
      const core::Vector3 n_S(std::sin(polar) * std::cos(a), std::sin(polar) * std::sin(a),
                              std::cos(polar));
      const core::Vector3 p_S = radius * n_S + core::Vector3(0, 0, z_offset);
      mesh.add_vertex(to_float(X_FS * p_S), to_float(X_FS.R * n_S), colour);
    }
  }
  stitch_rings(mesh, first, rings);
}

void append_sphere(TriangleMesh& mesh,
                   const core::Vector3& p_F,
                   double radius,
                   const Eigen::Vector3f& colour) {
  append_capsule(mesh, core::Transform::from_translation(p_F), radius, 0.0, colour);
}

void append_cylinder(TriangleMesh& mesh,
                     const core::Transform& X_FS,
                     double radius,
                     double length,
                     const Eigen::Vector3f& colour) {
  const std::uint32_t first = static_cast<std::uint32_t>(mesh.vertex_count());
  for (double z : {0.5 * length, -0.5 * length}) {
    for (int s = 0; s <= kRoundSegments; ++s) {
      const double a = 2 * std::numbers::pi * s / kRoundSegments;
      const core::Vector3 n_S(std::cos(a), std::sin(a), 0);
      mesh.add_vertex(to_float(X_FS * core::Vector3(radius * n_S + core::Vector3(0, 0, z))),
                      to_float(X_FS.R * n_S), colour);
    }
  }
  stitch_rings(mesh, first, 1);
  append_disc(mesh, X_FS, radius, 0.5 * length, true, colour);
  append_disc(mesh, X_FS, radius, -0.5 * length, false, colour);
}

void append_box(TriangleMesh& mesh,
                const core::Transform& X_FS,
                const core::Vector3& size,
                const Eigen::Vector3f& colour) {
  const core::Vector3 half = 0.5 * size;
  // each face: its normal axis and sign; the two other axes span it
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      core::Vector3 n_S = core::Vector3::Zero();
      n_S[axis] = sign;
      const Eigen::Vector3f n = to_float(X_FS.R * n_S);
      std::array<std::uint32_t, 4> corner{};
      for (int k = 0; k < 4; ++k) {
        core::Vector3 p_S = core::Vector3::Zero();
        p_S[axis] = sign * half[axis];
        p_S[u] = ((k == 1 || k == 2) ? 1.0 : -1.0) * half[u];
        p_S[v] = (k >= 2 ? 1.0 : -1.0) * half[v];
        corner[k] = mesh.add_vertex(to_float(X_FS * p_S), n, colour);
      }
      // counter-clockwise seen from outside
      if (sign > 0) {
        mesh.add_triangle(corner[0], corner[1], corner[2]);
        mesh.add_triangle(corner[0], corner[2], corner[3]);
      } else {
        mesh.add_triangle(corner[0], corner[2], corner[1]);
        mesh.add_triangle(corner[0], corner[3], corner[2]);
      }
    }
  }
}

void append_segment(TriangleMesh& mesh,
                    const core::Vector3& a_F,
                    const core::Vector3& b_F,
                    double radius,
                    const Eigen::Vector3f& colour) {
  const core::Vector3 d = b_F - a_F;
  const double length = d.norm();
  // the rotation taking +z onto the segment's direction
  const core::Matrix3 R =
      length > 0
          ? core::Matrix3(Eigen::Quaterniond::FromTwoVectors(core::Vector3::UnitZ(), d / length)
                              .toRotationMatrix())
          : core::Matrix3::Identity();
  append_capsule(mesh, core::Transform{R, 0.5 * (a_F + b_F)}, radius, length, colour);
}

namespace {

bool has_primitive(const std::vector<core::Geometry>& shapes) {
  return std::any_of(shapes.begin(), shapes.end(), [](const core::Geometry& g) {
    return g.shape != core::Geometry::Shape::kMesh;
  });
}

}  // namespace

const std::vector<core::Geometry>* primitive_shapes(const core::Model& model, int link) {
  if (has_primitive(model.visual[link])) return &model.visual[link];
  if (has_primitive(model.collision[link])) return &model.collision[link];
  return nullptr;
}

bool append_geometry(TriangleMesh& mesh,
                     const core::Transform& X_FS,
                     const core::Geometry& g,
                     const Eigen::Vector3f& colour) {
  switch (g.shape) {
    case core::Geometry::Shape::kCapsule:
      append_capsule(mesh, X_FS, g.radius, g.length, colour);
      return true;
    case core::Geometry::Shape::kSphere:
      append_capsule(mesh, X_FS, g.radius, 0.0, colour);
      return true;
    case core::Geometry::Shape::kCylinder:
      append_cylinder(mesh, X_FS, g.radius, g.length, colour);
      return true;
    case core::Geometry::Shape::kBox:
      append_box(mesh, X_FS, g.size, colour);
      return true;
    case core::Geometry::Shape::kMesh:
      return false;
  }
  return false;
}

}  // namespace io
