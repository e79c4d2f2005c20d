// Editing a finished Model: a Model is immutable, so an edit goes back through a ModelBuilder
// (every link with every field, in the model's depth-first order) and finalize() validates the
// result again.
#pragma once

#include <memory>

#include "core/model.hpp"
#include "core/model_builder.hpp"
#include "core/skin.hpp"

namespace core {

/// A builder holding every link of `model` (names, joints, ranges, inertias, geometry, display
/// names) and its gravity and source folder; finalize() rebuilds an equal model (inertias equal
/// to rounding: they go back through mass, centre of mass and inertia about the centre of mass).
ModelBuilder to_builder(const Model& model);

/// The same model with its root link welded to the world: the root joint becomes fixed at the
/// pose it has at q = neutral (its placement X_PJ). Returns `model` itself when the root joint
/// is already fixed.
std::shared_ptr<const Model> weld_root(const std::shared_ptr<const Model>& model);

/// A character file placed as a figure stands in the page (the root's placement is the file's
/// own choice, and robot descriptions put it at the world origin with the legs below the floor).
struct Grounded {
  std::shared_ptr<const Model> model;
  double lift = 0;       // metres the root's placement moved up (down when negative)
  bool floated = false;  // the fixed root became free
};

/// Places `model` on the ground: its root joint's placement X_PJ moves vertically so the lowest
/// point of world_bounds in the pose where posing starts (rest_configuration) is at y = 0. A fixed
/// root under which the figure reaches more than a quarter of its height (a legged figure: it
/// stands on its limbs, not on its root, unlike an arm bolted at its base) becomes free, so the
/// whole figure can be posed and pinned by its feet. A model without extent is returned as it is.
Grounded stand_on_ground(const std::shared_ptr<const Model>& model);

/// Places an imported figure and its motion on the ground: the root joint's placement X_PJ moves
/// vertically so the lowest point the figure reaches over `frames` (the rest configuration when
/// there are none) is at y = 0. The lowest point is that of the skinned mesh when `skin` has
/// vertices (what the page draws), else of the links' shapes (world_bounds). The frames need no
/// change: joint coordinates are relative to the placement, so the whole motion moves with it,
/// and so does a skin (its bind pose follows the links). A mesh of V vertices is skinned on at
/// most kGroundingVertexFrames / V frames spread evenly over the clip (always its first and last).
/// A figure without extent, or already on the ground to rounding, is returned as it is.
Grounded stand_motion_on_ground(const std::shared_ptr<const Model>& model,
                                const std::vector<Eigen::VectorXd>& frames,
                                const SkinnedMesh* skin);
inline constexpr double kGroundingVertexFrames = 2e7;

/// `model` with its root joint's placement X_PJ turned by the rotation `R` (world frame) about
/// the point `centre`: the figure, and any motion of it (its joint coordinates are relative to
/// the placement), turns in place about that point.
std::shared_ptr<const Model> turn_root(const Model& model, const Matrix3& R, const Vector3& centre);

}  // namespace core
