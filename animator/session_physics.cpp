// Session: physics while the scene simulates (animator/physics_session.hpp). The world starts at
// the pose shown and the pose follows it; a physics run adds no undo entry of its own: the pose
// it reaches belongs to the next edit (a drag, a pin, switching the effects off), and undoing an
// edit while physics runs starts the world again at the pose that edit restores.
#include "animator/session.hpp"

namespace animator {

void Session::sync_physics(bool restart) {
  if (!simulates(doc_.scene)) {
    // kinematic posing resumes at the document's pose: where the last tick left the figure
    // (no jump), or the pose an undo restored; pins do not pull it anywhere until the next edit
    if (physics_) settling_ = false;
    physics_.reset();
    return;
  }
  if (physics_ && !restart) {
    physics_->set_scene(doc_.scene);
    return;
  }
  physics_ = std::make_unique<PhysicsSession>(model_, doc_.scene, doc_.q);
  doc_.q = physics_->q();  // placed standing on the ground when the scene has contact
  refresh_kinematics();
}

void Session::physics_tick(double dt, TickResult& result) {
  physics_->set_tasks(doc_.pins, drag_ ? std::optional(drag_task()) : std::nullopt);
  physics_->advance(dt);
  doc_.q = physics_->q();
  refresh_kinematics();
  result.pose_changed = true;
}

}  // namespace animator
