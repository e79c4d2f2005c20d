// Animation clip files for the CLI: BVH read and written by io/bvh.hpp, glTF/GLB written by
// io/gltf.hpp, and skinned characters (.gltf, .glb, .fbx, .dae) read through the sandboxed
// assimp import (io/assimp_import.hpp). The kind is chosen by the file extension.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "core/skin.hpp"
#include "io/bvh.hpp"

namespace cli {

enum class ClipFormat { kBvh, kGltf, kGlb, kFbx, kDae };

/// The extension of `path`'s file name, lowercased, with its dot (".bvh"), or "".
std::string lower_extension(const std::string& path);
/// The format named by the extension of `path` (case-insensitive), or empty.
std::optional<ClipFormat> clip_format(const std::string& path);
/// True for formats a clip can be written to (.bvh, .gltf, .glb).
bool writable(ClipFormat f);

/// A character and one clip of it, as read from a file.
struct ClipFile {
  std::shared_ptr<const core::Model> model;
  core::Clip clip;
  std::optional<io::BvhLayout> bvh_layout;        // BVH input: names, channel orders, scale
  std::shared_ptr<const core::SkinnedMesh> skin;  // skinned input: the mesh
  std::string clip_name;                          // the file's animation name (may be empty)
  int clips_in_file = 1;
  std::string unit;  // BVH input: the unit chosen
  std::vector<std::string> warnings;
};

struct ClipReadOptions {
  std::optional<double> bvh_scale;  // metres per BVH file unit; empty: automatic
  std::optional<double> fps;  // resample to this rate; empty: the file's rate (30 for skinned)
  std::function<void(double)> progress;
};

/// Reads a clip file by extension. Skinned files keep their first animation (or the bind pose as
/// one frame when they have none, with a warning).
/// @throws core::ModelError naming the file and the rule broken
ClipFile read_clip_file(const std::string& path, const ClipReadOptions& options = {});

struct ClipWriteOptions {
  std::optional<std::string> bvh_order;  // e.g. "ZXY"
  std::optional<double> bvh_scale;       // metres per BVH file unit
  // glTF without a skinned mesh: the links' shapes as a mesh (the stick figure for a model
  // without shapes), or with stick_figure the stick figure instead; both false: skeleton only
  bool shape_mesh = true;
  bool stick_figure = false;
  std::function<void(double)> progress;
};

/// Writes `clip` of `source.model` (with its skin and BVH layout) by the extension of `path`,
/// atomically. @throws std::invalid_argument or std::system_error naming the path
void write_clip_file(const std::string& path,
                     const ClipFile& source,
                     const core::Clip& clip,
                     const ClipWriteOptions& options = {});

/// The clip resampled at `fps` frames per second from 0 to its duration (interpolated on the
/// manifold; the last frame is the clip's last when the duration is a whole number of frames).
core::Clip resample(const core::Model& model, const core::Clip& clip, double fps);

}  // namespace cli
