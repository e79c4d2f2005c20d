// A `pindrag solve` request as read (cli/solve_request.cpp) and run, kinematically by the IK
// solver or, with effects, in a simulated world (cli/solve_physics.hpp). Formats: docs/ik.md.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/model.hpp"
#include "ik/problem.hpp"
#include "ik/solver.hpp"
#include "sim/scene.hpp"

namespace cli {

struct DragSpec {
  ik::LinkTask task{.role = ik::kDrag};
  int release_at = -1;  // frame at which the drag is let go; -1: never
};

struct SolveSpec {
  std::shared_ptr<const core::Model> model;
  int frames = 120;
  ik::SolverSettings settings;  // settings.dt: the output frame period on both paths
  Eigen::VectorXd q;            // frame 0
  std::vector<DragSpec> drags;
  std::vector<ik::LinkTask> pins;
  std::vector<ik::JointReferenceTask> references;
  // physics: the request's effects (none: the kinematic path) and the fixed physics step (s)
  sim::Scene scene;
  double physics_dt = 1e-3;
  bool physics() const { return !scene.kinematic(); }
};

}  // namespace cli
