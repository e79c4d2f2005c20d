// Which physical effects a scene simulates (DESIGN.md §5). Posing is kinematic by default; the
// physics effects arrive with the simulation layer and are carried and saved until then.
#pragma once

namespace animator {

struct Scene {
  bool gravity = false;
  bool ground_contact = false;
  bool dynamic_pins = false;
  bool hard_limits = false;
  bool self_collision = false;

  bool kinematic() const {
    return !gravity && !ground_contact && !dynamic_pins && !hard_limits && !self_collision;
  }
  bool operator==(const Scene&) const = default;
};

}  // namespace animator
