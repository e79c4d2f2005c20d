// Import of skinned, animated characters (glTF 2.0 / GLB, FBX, COLLADA) through assimp, run in
// a resource-limited child process (io/sandbox.hpp): assimp 5.2.5 has known memory-safety
// bugs on hostile files (ecosystem.md §7.2), so it never runs in the caller's process. What
// comes back is our own data, validated again by the parent: a core::Model (the character JSON
// of io/character_json.hpp), a core::SkinnedMesh and core::Clips. docs/formats.md has the
// details. Inside: the child's work and the converter stages in io/assimp_child.hpp, the bytes
// it sends back in io/assimp_reply.hpp.
//
// The model: one link per bone of the skinned meshes (and per node between bones), named after
// its node (unnamed glTF nodes: assimp's "nodes[N]", N the glTF node index). The root is the
// deepest node above every bone, on a free joint whose placement is its bind pose in the world;
// every other link is on a spherical joint whose placement is its bind pose relative to its
// parent, so the neutral configuration is the bind pose. The animated transforms of the nodes
// above the root (an "Armature" node, axis conversions) are folded into the root's motion.
// Masses come from bone lengths (a slender cylinder per bone), scaled to a total mass. A file
// without skinned meshes whose animations move its nodes (a skeleton exported without its mesh,
// a rigid mechanism) imports too: the moved nodes stand for the bones, in their rest pose, and
// each mesh a node carries follows that node's link whole (io/assimp_rigid.hpp). In a skinned
// file, a mesh without bones carried by a node of the skeleton follows its link the same way.
//
// World: metres, Y up. glTF is both already; FBX lengths are scaled by UnitScaleFactor / 100
// (FBX units are centimetres times that factor) and its axes turned by the file's axis system.
//
// Clips: every animation, resampled at a fixed rate from its first to its last key (the last
// frame clamps to the end); assimp's ticks are converted with the animation's ticks per second
// (glTF: 1000, i.e. milliseconds; FBX: the file's frame rate). Between keys, positions and
// scales are interpolated linearly and rotations by slerp. Node scales and the offsets of
// non-root bones cannot be carried by spherical joints: their deviation from the bind pose is
// measured and reported (SkinnedImport::dropped_offset, warnings), and a bone whose offset moves
// by more than ImportOptions::translating_tolerance during a clip gets a free joint instead.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "core/skin.hpp"
#include "io/clip_budget.hpp"
#include "io/core_names.hpp"
#include "io/sandbox.hpp"

namespace io {

/// Resources the import may use; above them it stops with an error naming the file.
struct ImportLimits {
  std::size_t max_file_bytes = std::size_t{256} << 20;   // refused before the child starts
  std::size_t memory_bytes = std::size_t{512} << 20;     // child address space (RLIMIT_AS headroom)
  int cpu_seconds = 20;                                  // child CPU time (RLIMIT_CPU)
  double timeout_seconds = 60;                           // wall clock
  std::size_t max_reply_bytes = std::size_t{256} << 20;  // results the child may send back
};

struct ImportOptions {
  double frame_rate = 30;  // clip frames per second (> 0, <= 1000)
  double total_mass = 70;  // kg, shared by the links in proportion to their bone lengths
  // a non-root bone whose offset from its parent moves more than this (metres) during a clip
  // gets a free joint, so the clip is reproduced; below it the bone is spherical
  double translating_tolerance = 1e-3;
  // an animation beyond it (its key span at frame_rate; frames × the model's coordinates) is
  // refused before it is resampled
  ClipBudget budget;
};

/// One animation of the file, resampled.
struct ImportedClip {
  std::string name;       // the file's animation name (may be empty)
  double start_time = 0;  // file time (s) of frame 0: the animation's first key
  core::Clip clip;        // frames at 1 / frame_rate, of the imported model
};

struct SkinnedImport {
  std::shared_ptr<const Model> model;
  SkinnedMesh mesh;  // bones are link indices of `model`
  std::vector<ImportedClip> clips;
  double unit_scale = 1;  // metres per file unit applied to the file's lengths
  /// Per link (njoints; 0 for the world and the root): the largest distance over all clips
  /// between the bone's animated offset from its parent and its bind offset, which a spherical
  /// joint keeps (metres). Free (translating) joints reproduce their offsets: 0.
  std::vector<double> dropped_offset;
  std::vector<std::string> warnings;  // what was approximated or left out, each naming the file
};

/// Imports a skinned character from .gltf, .glb, .fbx or .dae (by extension, checked against
/// the file's first bytes) in a child process under `limits`. A .gltf may reference buffers in
/// its own folder; nothing outside that folder is opened.
/// @throws ModelError naming the file and what went wrong: missing, empty, too large, not the
///         format its extension says, rejected by assimp (with assimp's message), no skinned
///         mesh and no animation that moves a node, the child crashed / ran out of memory or CPU
///         time / timed out, or its reply was malformed
SkinnedImport import_skinned_file(const std::string& path,
                                  const ImportLimits& limits = {},
                                  const ImportOptions& options = {});

}  // namespace io
