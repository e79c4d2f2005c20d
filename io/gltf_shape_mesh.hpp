// The shape mesh of a glTF export (io/gltf.hpp): a character without a skinned mesh drawn with
// the primitive shapes of its links (io/shape_mesh.hpp), each vertex rigidly skinned to the link
// its shape belongs to. Internal to io/.
#pragma once

#include <vector>

#include "io/core_names.hpp"
#include "io/gltf_mesh.hpp"

namespace io::gltf_detail {

/// True when some link of `model` has a primitive shape (io::primitive_shapes).
bool has_primitive_shapes(const Model& model);

/// Every link's primitive shapes (its visual shapes, else its collision shapes) placed by
/// X_bind[i] (the link's world pose at the bind pose), vertices skinned to skin joint i - 1;
/// triangles of zero area are left out, and so are the vertices no triangle uses. A link without
/// a primitive shape gets its stick-figure boxes (append_link_sticks, half width `stick_radius`)
/// instead, so every link has vertices.
/// @throws std::invalid_argument naming the link when a shape gives a non-finite vertex
MeshArrays shape_mesh(const Model& model,
                      const std::vector<Transform>& X_bind,
                      double stick_radius);

}  // namespace io::gltf_detail
