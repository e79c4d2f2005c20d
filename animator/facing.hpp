// Which way a figure faces and which way is its up, and turning an opened figure upright and to
// face +Z, pindrag's convention (world Y up, a character faces +Z with its left towards +X).
//
// A figure's left is read from its names: the left and right hips and shoulders of a humanoid
// convention (animator/joint_names.hpp), else any links whose names differ only in a side word
// ("L"/"R", "Left"/"Right", any case: "leg_joint_L_1", "Bip01 R Thigh", "hip.L",
// "left_hip_pitch_link"; leg codes "FL_hip", "RH_KFE"), taking each limb's first pair below the
// root (hips, shoulders, a quadruped's four legs). The figure faces left × up, the direction in
// which its chest and toes point when its left is where the names say. A rig whose names tell no
// sides (glTF bones named "nodes[N]") faces where its toes point in its rest pose.
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

/// The name with its side word swapped ("LeftArm" → "RightArm", "leg_L_1" → "leg_R_1", and in a
/// four-legged robot's leg code "FL_hip" → "FR_hip", "RR_calf" → "RL_calf", "LH_KFE" → "RH_KFE")
/// and whether that word said left; std::nullopt when the name has no side word. Words are split at
/// anything but letters and digits and where lower case turns to upper case ("mixamorig:LeftArm"
/// reads mixamorig, Left, Arm; "LHip" reads L, Hip).
std::optional<std::pair<std::string, bool>> mirrored_name(const std::string& name);

/// The horizontal unit direction the figure faces in the pose of `data` (after forward
/// kinematics): left × up, with left the sum of the pairs' (left − right) world offsets.
/// std::nullopt when there are no pairs, or when that sum is within 30° of vertical (a figure
/// lying on its side faces no horizontal direction).
std::optional<core::Vector3> facing_from_sides(const core::Data& data,
                                               const std::vector<std::pair<int, int>>& pairs);

/// Which way a figure faces and what told it.
struct Facing {
  core::Vector3 direction;                 // horizontal, unit length
  std::vector<std::pair<int, int>> links;  // the (left, right) pairs, or (foot, toe) when by_toes
  bool by_toes = false;                    // read from the toes: the names tell no sides
};

/// The toes of a figure whose names tell no sides, found by shape in its rest pose: (parent, leaf)
/// for each leaf link in the lowest 15 % of the links' heights, below the root, whose bone from
/// its parent leans at least 15° from vertical (a toe or a foot pointing forward). Empty when
/// there are none, or when they do not point the same way horizontally.
std::vector<std::pair<int, int>> toe_links(const core::Model& model);

/// Where the toes point in the rest pose, carried into the pose of `data` by the root's rotation
/// (horizontal, unit length); std::nullopt without toes, or when that is within 30° of vertical.
std::optional<core::Vector3> facing_from_toes(const core::Model& model,
                                              const core::Data& data,
                                              const std::vector<std::pair<int, int>>& toes);

/// The direction the figure faces in the pose of `data` (after forward kinematics): from its
/// left and right (facing_from_sides) when its names tell them, else from where its toes point in
/// the rest pose, carried into this pose by the root's rotation. std::nullopt when neither tells,
/// or the direction is within 30° of vertical.
std::optional<Facing> facing_of(const core::Model& model, const core::Data& data);

/// The figure's up in its rest pose, by name: the mean direction from its feet to its hips and
/// from its hips to its head (else its neck, else its chest) as a humanoid convention names them.
/// std::nullopt when they are not named, or when the two directions are more than 45° apart (a
/// four-legged figure, its spine level over its legs, has no such up).
std::optional<core::Vector3> rest_up(const core::Model& model);

/// Stands a figure authored with another up axis upright. When its rest pose's up (rest_up) is
/// more than 45° from +Y and within 45° of ±X, −Y or ±Z (a capture exported Z up lies on its
/// back), the root's placement turns by the quarter or half turn that takes that axis to +Y, about
/// the root's origin in the rest pose; else `model` itself is returned. The rest pose tells the
/// file's convention: a clip that starts lying on the floor keeps its first frame.
std::shared_ptr<const core::Model> stand_upright(const std::shared_ptr<const core::Model>& model);

/// A figure turned to face +Z.
struct Faced {
  std::shared_ptr<const core::Model> model;
  double turn = 0;     // radians the figure turned about the vertical (right-handed about +Y)
  bool known = false;  // its names or its toes told which way it faced
};

/// Turns `model` about the vertical line through its root's origin in configuration `q` so that it
/// faces +Z in `q` (the root's placement turns; the joint coordinates of any clip are unchanged
/// and its whole motion turns with it). Returns `model` itself when its facing is unknown or
/// already +Z to rounding.
Faced face_forward(const std::shared_ptr<const core::Model>& model, const Eigen::VectorXd& q);

}  // namespace animator
