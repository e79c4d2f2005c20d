// The animation stage of the skinned import (io/assimp_import.hpp), run in the child: every
// animation resampled at a fixed rate from its first to its last key (the last frame clamps to
// the end). assimp's ticks become seconds by the animation's ticks per second. Between keys,
// positions and scales are interpolated linearly and rotations by slerp. The nodes above the
// root are animated too and folded into the root's motion. Node scales and the offsets of
// non-root bones cannot be carried by spherical joints: their deviation from the bind pose is
// measured (Motion::dropped), and a bone whose offset moves by more than
// ImportOptions::translating_tolerance gets a free joint instead. Internal to io/.
#pragma once

#include <vector>

#include "io/assimp_import.hpp"
#include "io/assimp_scene.hpp"
#include "io/assimp_skeleton.hpp"

namespace io::assimp_detail {

/// One animation of the file: its channels per node and its sampling.
struct AnimInfo {
  const aiAnimation* anim = nullptr;
  std::vector<const aiNodeAnim*> channel_of_node;  // per node, or null
  double ticks_per_second = 25;
  double start = 0, end = 0;  // ticks of the first and last key
  int frames = 0;             // after resampling at the frame rate
};

/// The channels, key span and frame count of `a` (a channel without a node gets a warning).
/// @throws std::runtime_error for non-finite or decreasing key times, or a length or frame count
///         beyond `budget`
AnimInfo anim_info(const aiAnimation& a,
                   const SceneNodes& nodes,
                   double frame_rate,
                   const ClipBudget& budget,
                   Warnings& warnings);

/// Refuses an animation beyond `budget` with `per_frame` numbers per frame (0: length and frame
/// count only). @throws std::runtime_error naming the animation and the limit
void check_budget(const AnimInfo& info,
                  const ClipBudget& budget,
                  double frame_rate,
                  std::int64_t per_frame);

/// File time (ticks) of frame k: start + k / frame_rate seconds, clamped to the last key.
double tick_of_frame(const AnimInfo& info, int k, double frame_rate);

/// Local transform of `node` at time t (ticks) of `channel`: T · R · S from the keys, each
/// component its rest value where the channel has no keys; the rest transform without a channel.
Matrix4 local_at(const Node& node, const aiNodeAnim* channel, double t);

/// Rigid world poses of the links (our world) at a time of an animation.
class LinkPoses {
 public:
  LinkPoses(const SceneNodes& nodes, const Skeleton& skeleton, const WorldAxes& world);
  /// Poses into `out` (one per link); the worst scale deviation raises `scale_error`.
  void at(const AnimInfo& info, double t, std::vector<Transform>& out, double& scale_error);

 private:
  const SceneNodes& nodes_;
  const Skeleton& skeleton_;
  const WorldAxes& world_;
  std::vector<Matrix4> global_;  // scratch: file world per link
};

/// What the clips do to the skeleton.
struct Motion {
  std::vector<AnimInfo> anims;  // every animation of the file, in its order
  std::vector<char> is_free;    // per link: the root, and bones whose offset translates
  // per link: largest distance between the animated and the bind offset that a spherical joint
  // keeps (metres); 0 for the root and for free joints
  std::vector<double> dropped;
};

/// Samples every animation at the frame rate: which bones translate, how far spherical ones
/// drift, and whether the clips scale bones (each approximation a warning).
Motion sample_motion(const aiScene& scene,
                     const SceneNodes& nodes,
                     const Skeleton& skeleton,
                     LinkPoses& poses,
                     const ImportOptions& options,
                     Warnings& warnings);

/// The clips of `model` (built from `skeleton`; model_link maps links to its link indices):
/// each animation's frames as configurations, joint motion X_PJ⁻¹ · (pose in the parent link).
std::vector<ImportedClip> build_clips(const Model& model,
                                      const std::vector<int>& model_link,
                                      const Skeleton& skeleton,
                                      const Motion& motion,
                                      LinkPoses& poses,
                                      double frame_rate);

}  // namespace io::assimp_detail
