// The physical effects a scene asks for (DESIGN.md §5). Posing is kinematic by default: with no
// effect switched on, the world simulates nothing and costs nothing.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sim {

enum class Effect {
  kGravity,        // the model's gravity acts on every body
  kGroundContact,  // soft contact against the ground plane and the static boxes (Yamane ch. 6)
  kFriction,       // static and dynamic friction at those contacts (needs ground_contact or
                   // self_collision to have any effect)
  kHardLimits,     // 1-DOF limits and swing–twist ranges as stops
  kSelfCollision,  // soft contact between the links of one body
  kDynamicPins,    // pins and the drag act at acceleration level (Yamane ch. 9)
};
constexpr int kEffectCount = 6;
constexpr std::array<Effect, kEffectCount> kAllEffects = {
    Effect::kGravity,    Effect::kGroundContact, Effect::kFriction,
    Effect::kHardLimits, Effect::kSelfCollision, Effect::kDynamicPins};

/// "gravity", "ground_contact", "friction", "hard_limits", "self_collision", "dynamic_pins"
const char* to_string(Effect e);
std::optional<Effect> effect_from_string(std::string_view name);

struct Scene {
  bool gravity = false;
  bool ground_contact = false;
  bool friction = false;
  bool hard_limits = false;
  bool self_collision = false;
  bool dynamic_pins = false;

  bool has(Effect e) const;
  void set(Effect e, bool on);
  /// No effect at all: pure kinematic posing.
  bool kinematic() const;
  /// The effects switched on, in kAllEffects order.
  std::vector<Effect> effects() const;
  /// Contacts of any kind are searched for.
  bool contacts() const { return ground_contact || self_collision; }
  bool operator==(const Scene&) const = default;

  /// The scene with exactly these effects. @throws std::invalid_argument naming an unknown name
  static Scene from_names(const std::vector<std::string>& names);
};

}  // namespace sim
