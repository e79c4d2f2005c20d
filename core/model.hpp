// The immutable kinematic tree of a character: joints, links, inertias, ranges and geometry.
// Built and validated by ModelBuilder (core/model_builder.hpp); never changed afterwards, so one
// Model serves any number of sessions and threads, each with its own State and Data.
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/spatial.hpp"

namespace core {

/// Joint types. Velocities of spherical and free joints are expressed in the child (joint)
/// frame; a spherical joint stores a unit quaternion (w, x, y, z) in q, a free joint a position
/// (in the parent frame) followed by a unit quaternion. Free-joint velocities are [ω; v].
enum class JointType { kFixed, kRevolute, kPrismatic, kSpherical, kFree };

constexpr int joint_nq(JointType t) {
  switch (t) {
    case JointType::kFixed:
      return 0;
    case JointType::kRevolute:
    case JointType::kPrismatic:
      return 1;
    case JointType::kSpherical:
      return 4;
    case JointType::kFree:
      return 7;
  }
  return 0;
}
constexpr int joint_nv(JointType t) {
  switch (t) {
    case JointType::kFixed:
      return 0;
    case JointType::kRevolute:
    case JointType::kPrismatic:
      return 1;
    case JointType::kSpherical:
      return 3;
    case JointType::kFree:
      return 6;
  }
  return 0;
}
/// "fixed", "revolute", "prismatic", "spherical", "free"
const char* to_string(JointType t);
std::optional<JointType> joint_type_from_string(std::string_view s);

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// Range of a 1-DOF joint (radians or metres) and its actuator limits.
struct JointLimits {
  double lower = -kInfinity;
  double upper = kInfinity;
  double velocity = kInfinity;
  double effort = kInfinity;
  bool operator==(const JointLimits&) const = default;
};

/// Motion range of a spherical joint in swing–twist form (Yamane §8.3.5, digest §2.5).
/// The swing (a_y, a_z) is the vector part of the swing quaternion about the nominal link
/// direction, the x axis of the range frame. Allowed swings are the union of the triangles; each
/// vertex carries twist limits, interpolated barycentrically inside a triangle. Twist limits may
/// reach beyond ±π (a range that straddles the twist wrap). An empty range means unlimited.
struct SphericalRange {
  /// rotation from the range frame (x = nominal link direction) to the joint frame
  Quaternion frame = Quaternion::Identity();
  std::vector<Eigen::Vector2d> swing;  // vertices (a_y, a_z), inside the unit disk
  std::vector<std::array<int, 3>> triangles;
  std::vector<double> twist_lower;  // per vertex, radians
  std::vector<double> twist_upper;  // per vertex, radians

  bool empty() const { return triangles.empty(); }
  bool operator==(const SphericalRange& o) const;
};

/// A conservative inner region of a spherical range, derived from it: every swing with
/// |a| <= swing_radius and twist in [twist_lower, twist_upper] is inside (used to skip the
/// triangle search for joints well inside their ranges).
struct RangeInnerBounds {
  double swing_radius = -1;  // negative: no inner disk (the nominal direction is not inside)
  double twist_lower = 0;
  double twist_upper = -1;
  /// sin(θ/2) for the largest angle θ such that every rotation by at most θ is inside (a rotation
  /// by θ swings the nominal direction and twists about it by at most θ each); negative: none
  double rotation_sin_half = -1;
  bool operator==(const RangeInnerBounds&) const = default;
};

/// A collision or display shape attached to a link. Capsules and cylinders run along the
/// shape frame's z axis; `length` is the distance between the capsule's end-sphere centres or
/// the cylinder's full height; `size` holds a box's full extents. Meshes are referenced by a
/// path relative to the model's own folder.
struct Geometry {
  enum class Shape { kCapsule, kSphere, kBox, kCylinder, kMesh };
  Shape shape = Shape::kSphere;
  Transform X_LinkShape;
  double radius = 0;
  double length = 0;
  Vector3 size = Vector3::Zero();
  std::string mesh;
  Vector3 scale = Vector3::Ones();
  bool operator==(const Geometry& o) const = default;
};
const char* to_string(Geometry::Shape s);
std::optional<Geometry::Shape> shape_from_string(std::string_view s);

/// Joint 0 is the world. Joint i >= 1 connects link i to link parent[i] (parent[i] < i, links
/// in depth-first order so a subtree is a contiguous index range).
struct Model {
  std::string name;
  int njoints = 1;  // including the world
  int nq = 0;
  int nv = 0;
  Vector3 gravity{0, -9.81, 0};  // Y up
  std::string source_dir;        // folder the model was loaded from; meshes resolve inside it

  // topology (njoints)
  std::vector<int> parent;
  std::vector<int> subtree_end;  // the subtree of i is [i, subtree_end[i])
  // names (njoints); display names may be empty
  std::vector<std::string> link_name;
  std::vector<std::string> joint_name;
  std::vector<std::string> display_name;
  // joints (njoints)
  std::vector<JointType> joint_type;
  std::vector<Transform> X_PJ;  // joint frame in the parent link frame at the neutral configuration
  std::vector<Vector3> axis;    // unit axis in the joint frame (revolute, prismatic)
  std::vector<int> axis_index;  // 0, 1, 2 when axis is +x, +y, +z exactly, else -1 (fast paths)
  std::vector<char> placement_is_translation;  // X_PJ.R is exactly the identity (fast paths)
  std::vector<int> idx_q;                      // first configuration coordinate of each joint
  std::vector<int> idx_v;                      // first velocity coordinate of each joint
  std::vector<JointLimits> limits;
  std::vector<SphericalRange> spherical_range;
  std::vector<RangeInnerBounds> range_inner;     // derived from spherical_range
  std::vector<Quaternion> standard_orientation;  // rest orientation of spherical joints
  std::vector<double> ik_weight;                 // relative cost of moving the joint in IK
  std::vector<std::optional<double>> ik_gain;    // feedback gain (1/s); empty: solver default
  // links (njoints); the link frame is the joint frame
  std::vector<SpatialInertia> inertia;
  std::vector<std::vector<Geometry>> collision;
  std::vector<std::vector<Geometry>> visual;
  // velocity coordinates (nv)
  std::vector<int> joint_of_v;
  std::vector<int> parent_v;  // the velocity coordinate this one hangs from, or -1 (sparse LTDL)
  // the first coordinate of the unbranched run ending at this one: the ancestors of k are
  // chain_start_v[k]..k, then those of parent_v[chain_start_v[k]] (runs the LTDL loops stream)
  std::vector<int> chain_start_v;

  /// Index of the link (= its joint) with this link name, or -1.
  int link_index(std::string_view link) const;
  /// Index of the joint with this joint name, or -1.
  int joint_index(std::string_view joint) const;
  /// The last velocity coordinate on the root path of `link`: its joint's last, or the nearest
  /// ancestor's when its joint has none (fixed); -1 when no joint on the path moves. The path's
  /// coordinates are this one and its ancestors (parent_v).
  int path_last_v(int link) const;
  double total_mass() const;
  int nlinks() const { return njoints - 1; }
  bool operator==(const Model& o) const;
};

/// f(first, count) for each run of consecutive velocity coordinates among k and its ancestors,
/// from k up to the root (nothing when k < 0), given Model::chain_start_v and Model::parent_v. A
/// run is an unbranched stretch of the tree (a limb, a chain), so the loops over a root path
/// stream through contiguous memory instead of waiting on each parent's index.
template <typename F>
inline void for_each_ancestor_run(const int* chain_start_v, const int* parent_v, int k, F&& f) {
  for (int j = k; j >= 0;) {
    const int c = chain_start_v[j];
    f(c, j - c + 1);
    j = parent_v[c];
  }
}

template <typename F>
inline void for_each_ancestor_run(const Model& model, int k, F&& f) {
  for_each_ancestor_run(model.chain_start_v.data(), model.parent_v.data(), k, f);
}

}  // namespace core
