// A BVH (Biovision Hierarchy) file in memory, as written: the hierarchy of ROOT, JOINTs and End
// Sites with their OFFSETs and channel lists, the motion values in file units and degrees, the
// limits that the reader and the writer keep, and the file's own forward kinematics.
// docs: ../shared/reference/ecosystem.md §1.
//
// Channels: every joint keeps its own channel list in file order. A rotation is the product of
// the elementary rotations in file order (intrinsic): channels `Zrotation Xrotation Yrotation`
// with values a, b, c give R = Rz(a) Rx(b) Ry(c). Position channels are the joint's local
// translation and replace the matching OFFSET component (Blender, MotionBuilder and assimp read
// them this way; three.js adds them to OFFSET, which agrees whenever OFFSET is zero, as it is for
// every joint with position channels that io/bvh_writer.hpp emits).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "io/core_names.hpp"

namespace io {

/// Largest BVH file read (bytes); larger files are refused before reading.
constexpr std::size_t kMaxBvhBytes = std::size_t{256} << 20;
/// Longest line accepted (bytes): kMaxBvhJoints joints × 6 values fit with room to spare.
constexpr std::size_t kMaxBvhLineBytes = std::size_t{1} << 20;
/// Most ROOT/JOINT entries, and most End Sites, in one file.
constexpr int kMaxBvhJoints = 4096;
/// Largest `Frames:` accepted (about 23 hours at 120 fps).
constexpr long kMaxBvhFrames = 10'000'000;
/// Largest magnitude of an OFFSET component or a motion value.
constexpr double kMaxBvhMagnitude = 1e9;
/// Largest `Frame Time:` accepted (seconds).
constexpr double kMaxBvhFrameTime = 3600.0;

enum class BvhChannel : std::uint8_t {
  kXposition,
  kYposition,
  kZposition,
  kXrotation,
  kYrotation,
  kZrotation
};
/// "Xposition", ..., "Zrotation" (the exact case writers use).
const char* to_string(BvhChannel c);
inline bool is_rotation(BvhChannel c) { return c >= BvhChannel::kXrotation; }
/// 0, 1, 2 for X, Y, Z.
inline int channel_axis(BvhChannel c) { return static_cast<int>(c) % 3; }

/// One ROOT, JOINT or End Site of a BVH hierarchy.
struct BvhNode {
  enum class Kind : std::uint8_t { kRoot, kJoint, kEndSite };
  Kind kind = Kind::kJoint;
  std::string name;                  // empty for an End Site
  int parent = -1;                   // index in BvhDocument::nodes; -1 for the ROOT
  Vector3 offset = Vector3::Zero();  // file units, in the parent's frame
  std::vector<BvhChannel> channels;  // file order; empty for an End Site
  int first_value = 0;               // index of its first channel within a frame's values
  int line = 0;                      // line of its ROOT / JOINT / End keyword (0 when written)
  bool is_end_site() const { return kind == Kind::kEndSite; }
};

/// A BVH file as written: hierarchy, frame count and time, values in file units and degrees.
struct BvhDocument {
  std::vector<BvhNode> nodes;  // depth-first file order; nodes[0] is the ROOT
  int channels = 0;            // values per frame (sum of every joint's CHANNELS)
  int frames = 0;
  double frame_time = 1.0 / 30.0;
  std::vector<double> values;  // frames × channels, row-major
  std::vector<std::string> warnings;

  const double* frame(int f) const {
    return values.data() + static_cast<std::size_t>(f) * channels;
  }
  int joint_count() const;
};

/// World pose of every node (file units, file order) for frame f, or for the rest pose (every
/// channel zero, i.e. OFFSETs only) when f < 0. An End Site has its joint's rotation.
std::vector<Transform> bvh_world_poses(const BvhDocument& doc, int frame);
/// Rotation of one joint from its channel values (R = product in file order).
Matrix3 bvh_joint_rotation(const BvhNode& node, const double* frame_values);
/// Local translation of one joint: its OFFSET with the components that have position channels
/// replaced by their values.
Vector3 bvh_joint_translation(const BvhNode& node, const double* frame_values);

/// Vertical (Y) and largest extent of the rest skeleton over all nodes (file units).
struct BvhExtent {
  double height = 0;
  double largest = 0;
};
BvhExtent bvh_rest_extent(const BvhDocument& doc);

}  // namespace io
