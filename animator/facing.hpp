// Which way a figure faces, and turning an opened figure to face +Z, pindrag's convention (world
// Y up, a character faces +Z with its left towards +X).
//
// A figure's left is read from its names: the left and right hips and shoulders of a humanoid
// convention (animator/joint_names.hpp), else any links whose names differ only in a side word
// ("L"/"R", "Left"/"Right", any case: "leg_joint_L_1", "Bip01 R Thigh", "hip.L",
// "left_hip_pitch_link"), taking each limb's first pair below the root (hips, shoulders, a
// quadruped's four legs). The figure faces left × up, the direction in which its chest and toes
// point when its left is where the names say.
#pragma once

#include <Eigen/Dense>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"

namespace animator {

/// Pairs (left link, right link) whose lateral offset tells which way the figure faces: the hips
/// and shoulders of a recognised humanoid convention, else the first pair of each limb matched by
/// side words in the names. Empty when the names tell no sides.
std::vector<std::pair<int, int>> left_right_pairs(const core::Model& model);

/// The name with its side word swapped ("LeftArm" → "RightArm", "leg_L_1" → "leg_R_1") and
/// whether that word said left; std::nullopt when the name has no side word. Words are split at
/// anything but letters and digits and where lower case turns to upper case ("mixamorig:LeftArm"
/// reads mixamorig, Left, Arm; "LHip" reads L, Hip).
std::optional<std::pair<std::string, bool>> mirrored_name(const std::string& name);

/// The horizontal unit direction the figure faces in the pose of `data` (after forward
/// kinematics): left × up, with left the sum of the pairs' (left − right) world offsets.
/// std::nullopt when there are no pairs, or when that sum is within 30° of vertical (a figure
/// lying on its side faces no horizontal direction).
std::optional<core::Vector3> facing_direction(const core::Data& data,
                                              const std::vector<std::pair<int, int>>& pairs);

/// A figure turned to face +Z.
struct Faced {
  std::shared_ptr<const core::Model> model;
  double turn = 0;     // radians the figure turned about the vertical (right-handed about +Y)
  bool known = false;  // its names told which way it faced
};

/// Turns `model` about the vertical line through its root's origin in configuration `q` so that it
/// faces +Z in `q` (the root's placement turns; the joint coordinates of any clip are unchanged
/// and its whole motion turns with it). Returns `model` itself when its facing is unknown or
/// already +Z to rounding.
Faced face_forward(const std::shared_ptr<const core::Model>& model, const Eigen::VectorXd& q);

}  // namespace animator
