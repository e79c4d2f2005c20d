// The session's figure in a simulated world: while the scene has an effect that moves it, the
// session's tick advances a sim::World instead of the kinematic solver, and the pose follows the
// world's body 0 (DESIGN.md §5). With dynamic_pins, the session's pins and the live drag act at
// acceleration level (Yamane ch. 9), and every joint is pulled toward the pose physics started
// from, so the figure keeps its posture while it stands.
//
// Thread contract: as Session's (one thread at a time).
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "animator/pin.hpp"
#include "core/data.hpp"
#include "core/model.hpp"
#include "ik/task.hpp"
#include "sim/scene.hpp"
#include "sim/world.hpp"

namespace animator {

/// The ground's push at one contact pair: where it acts and the force (N).
struct ContactArrow {
  core::Vector3 point = core::Vector3::Zero();
  core::Vector3 force = core::Vector3::Zero();
};

/// What the page draws while physics runs.
struct PhysicsMeasures {
  core::Vector3 com = core::Vector3::Zero();
  std::optional<core::Vector3> cop;            // empty when nothing presses on the ground
  std::vector<core::Vector3> support_polygon;  // on the ground plane
  std::vector<ContactArrow> contacts;          // ground contact pairs of the figure
  bool balanced = false;                       // the centre of mass over the support polygon
  bool fallen = false;  // down: its pins have let go (sim/fall_response.hpp) until an undo
  /// Microseconds each effect cost during the last advance (one displayed frame), by
  /// sim::kAllEffects order, and all of the world's steps together.
  std::array<double, sim::kEffectCount> effect_us{};
  double total_us = 0;
};

/// True when a scene moves the figure (an effect other than friction): physics then runs.
bool simulates(const sim::Scene& scene);

class PhysicsSession {
 public:
  /// A world holding the figure at q, at rest; standing on the ground when the scene has
  /// ground contact (sim::standing_configuration). @throws sim::SimError (a bad model)
  PhysicsSession(std::shared_ptr<const core::Model> model,
                 const sim::Scene& scene,
                 const Eigen::VectorXd& q);

  /// Changes the effects; the world keeps its state.
  void set_scene(const sim::Scene& scene);
  /// The tasks of the dynamic-pins problem for the next advance: the session's pins and the
  /// drag (nullopt: none), beside the joint references made when physics started.
  void set_tasks(const std::vector<Pin>& pins, const std::optional<ik::LinkTask>& drag);
  /// Advances the world by dt seconds of wall time; the measures then describe its end.
  void advance(double dt);

  /// The figure's configuration in the world.
  const Eigen::VectorXd& q() const { return world_.body(0).q; }
  const sim::World& world() const { return world_; }
  /// The posture the joint references hold: the pose physics started from, then the one each
  /// drag leaves.
  const Eigen::VectorXd& reference() const { return reference_; }
  PhysicsMeasures measures() const;

 private:
  std::shared_ptr<const core::Model> model_;
  sim::World world_;
  Eigen::VectorXd reference_;
  // the links it stood on when physics started, and their orientations then
  std::vector<std::pair<int, core::Quaternion>> supports_;
  bool dragging_ = false;
  mutable core::Data data_;        // scratch of measures()
  sim::StageTimers frame_timers_;  // the last advance's
  ik::Problem problem_;
};

}  // namespace animator
