// Editing a finished Model: a Model is immutable, so an edit goes back through a ModelBuilder
// (every link with every field, in the model's depth-first order) and finalize() validates the
// result again.
#pragma once

#include <memory>

#include "core/model.hpp"
#include "core/model_builder.hpp"

namespace core {

/// A builder holding every link of `model` (names, joints, ranges, inertias, geometry, display
/// names) and its gravity and source folder; finalize() rebuilds an equal model (inertias equal
/// to rounding: they go back through mass, centre of mass and inertia about the centre of mass).
ModelBuilder to_builder(const Model& model);

/// The same model with its root link welded to the world: the root joint becomes fixed at the
/// pose it has at q = neutral (its placement X_PJ). Returns `model` itself when the root joint
/// is already fixed.
std::shared_ptr<const Model> weld_root(const std::shared_ptr<const Model>& model);

}  // namespace core
