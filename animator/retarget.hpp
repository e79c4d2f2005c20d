// Retargeting: a clip of one skeleton played by another character.
//
// 1. Correspondence (animator/joint_names.hpp): source joints and target links paired by the
//    body part their names say, with the user's mapping over the guesses.
// 2. Rest alignment by bone directions: each mapped target link gets, per frame, the world
//    orientation R_t = R_s · R_s0ᵀ · A · R_t0 (R_s source link in the world, R_s0 and R_t0 the
//    two links at rest). A is the rotation that turns the target's rest bones onto the source's
//    rest bones (the directions to the next mapped links down the tree; two of them fix the twist
//    too), so a T-pose source and an arms-down target agree on where a bone points, not on local
//    angles. Joint values follow from the world orientations, parent first. Where the target
//    has fewer degrees of freedom the joint above makes up for them: a hinge bends to point its
//    bone and the link above it turns about its own bone to bring the bend into the hinge's
//    plane; a link welded to a ball joint has the ball joint turn so the joints below come
//    closest; unmapped spine and neck joints share the turn between the mapped links around them.
// 3. Root motion: the hip centre (between the thigh joints) follows the source's, scaled by the
//    leg-length ratio (thigh + shin of the target over the source's), from the world origin (the
//    floor's height is kept, scaled, so a round trip comes back at the clip's height).
// 4. Feet: contacts are detected in the source (a foot or toe link low, slow and within
//    contact_stillness of where it is for the whole contact), and become pins on the target link
//    held where the bones put it on average over the contact; the offset from the free path is
//    eased in and out, and the other link of the foot moves by the same offset. Every frame
//    starts from the retargeted pose (joints inside their ranges) and is solved by ik::Solver
//    (the settings of editing in motion): held contacts on level 1, joint ranges on level 2,
//    hands, head and free feet pinned to where the bone directions put them on level 3 with the
//    retargeted joint values as weak references. A frame whose held contacts would carry a joint
//    out of its range is solved again with the contacts on level 3. So the target's ranges hold
//    and its bone lengths are its own (the model is rigid).
#pragma once

#include <string>
#include <vector>

#include "animator/joint_names.hpp"
#include "core/clip.hpp"
#include "core/model.hpp"

namespace animator {

struct RetargetOptions {
  std::vector<MappingEntry> mapping;  // over the guessed correspondence
  std::string mapping_origin = "mapping";
  // a source foot or toe link is in contact while its lowest point is within contact_height of
  // the floor and its joint moves slower than contact_speed (both for a 0.9 m leg; scaled by
  // the source's leg length), for at least min_contact_time
  double contact_height = 0.05;    // m
  double contact_speed = 0.3;      // m/s
  double min_contact_time = 0.05;  // s
  // a contact's joint stays within this distance of where it is for the whole contact (m, for a
  // 0.9 m leg): a foot rolling over its toes is planted by its toes, not by its ankle
  double contact_stillness = 0.01;
  double contact_blend_time = 0.1;  // s: pins ease from the free path onto the contact
  int iterations = 8;               // solver iterations per frame
  int first_frame_iterations = 60;  // the first frame (no frame before it) gets more
};

struct FootContact {
  int target_link = 0;
  int source_link = 0;
  int first = 0, last = 0;  // frames, inclusive
  double slide = 0;         // m: largest distance of the target link from where the contact began
  double source_slide = 0;  // m: the same for the source link, times the leg-length ratio
};

struct RetargetReport {
  std::vector<std::pair<int, int>> mapping;  // (source link, target link), target order
  std::vector<int> unmapped_source;          // moving source joints that drive nothing
  std::vector<int> unmapped_target;          // moving target links no joint drives
  std::string source_convention, target_convention;
  double source_leg_length = 0, target_leg_length = 0;
  double scale = 1;         // target over source leg length: root motion is scaled by it
  double source_floor = 0;  // m: the floor's height in the source clip
  std::vector<FootContact> contacts;
  double max_foot_slide = 0;       // m, over the contacts
  double max_range_violation = 0;  // rad or m, over every joint and frame
  int frames_out_of_range = 0;     // frames with a joint more than kRangeTolerance out
  double max_effector_error = 0;   // m: hands, head and feet off their retargeted paths
};

/// A joint this far out of its range (rad or m) counts as out of range in the report.
constexpr double kRangeTolerance = 1e-3;

struct RetargetResult {
  core::Clip clip;  // frames of the target, the source's frame time
  RetargetReport report;
};

/// Retargets `clip` of `source` onto `target`.
/// @throws std::invalid_argument naming the rule broken: a mapping entry (see apply_mapping),
///         a skeleton without recognisable hips and legs, a target whose root is not free
RetargetResult retarget(const core::Model& source,
                        const core::Clip& clip,
                        const core::Model& target,
                        const RetargetOptions& options = {});

}  // namespace animator
