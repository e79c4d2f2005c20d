// glTF 2.0 export (.gltf with an embedded base64 buffer, or binary .glb) of a character, its
// clip and its skinned mesh. docs/formats.md describes what is written and why. The document
// is built as a tinygltf::Model and serialized by tinygltf (Debian's libtinygltf, 2.7), which
// also writes the base64 data URI and the GLB container.
//
// What a file holds:
//  - one node per link (fixed joints included) with translation/rotation (never `matrix`), in a
//    hierarchy that mirrors the model; the root node carries the root joint's world-relative
//    transform, so node world matrices equal core::forward_kinematics for every frame;
//  - `skins[0]` listing every link node (even with no mesh: viewers then build a skeleton), with
//    inverse bind matrices from the neutral pose, or the skinned mesh's own when one is given;
//  - with a clip: one animation, one LINEAR sampler per animated channel, one key per frame,
//    times k·frame_time starting at 0, hemisphere-continuous unit quaternions;
//  - with a skinned mesh: positions, normals, JOINTS_0 (unsigned short), WEIGHTS_0 (float,
//    summing to 1), a material with its base colour, on a root mesh node with an identity TRS;
//  - optionally a shape mesh: every link's primitive shapes (capsules, spheres, boxes,
//    cylinders; its visual shapes, else its collision shapes) at the bind pose, each vertex
//    rigidly skinned to its link, with normals and a light grey material; a link without a
//    shape gets its stick-figure boxes, and a model without any shape the whole stick figure;
//  - optionally a stick-figure mesh: a thin box per bone, rigidly skinned to its link, so any
//    viewer shows a bare skeleton.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "core/skin.hpp"
#include "io/core_names.hpp"

namespace io {

struct GltfExportOptions {
  std::string name;                   // scene and animation name; empty: the model's name
  bool shape_mesh = false;            // add the links' shapes as a mesh skinned rigidly to them
  bool stick_figure = false;          // add a box-per-bone mesh skinned rigidly to the links
  double stick_radius = 0.01;         // half width of a stick-figure box (m)
  std::string generator = "pindrag";  // asset.generator
};

/// The glTF JSON document with the binary buffer embedded as a base64 data URI.
/// @throws std::invalid_argument naming the frame, link or vertex when the clip does not fit the
///         model (nq, finite values, unit quaternions) or the mesh is inconsistent
std::string write_gltf(const Model& model,
                       const Clip* clip,
                       const SkinnedMesh* skin,
                       const GltfExportOptions& options = {});

/// The same document as binary glTF (GLB: header, JSON chunk, BIN chunk; 4-byte aligned).
/// @throws std::invalid_argument as write_gltf
std::vector<std::uint8_t> write_glb(const Model& model,
                                    const Clip* clip,
                                    const SkinnedMesh* skin,
                                    const GltfExportOptions& options = {});

/// Writes `.gltf` (JSON, embedded buffer) or `.glb` (binary) by the extension of `path`
/// (case-insensitive), atomically: a temporary file in the same folder, fsync, rename.
/// @throws std::invalid_argument for another extension or bad input (message names the path);
///         std::system_error naming the path when the file cannot be written
void save_gltf_file(const std::string& path,
                    const Model& model,
                    const Clip* clip,
                    const SkinnedMesh* skin,
                    const GltfExportOptions& options = {});

}  // namespace io
