#include "sim/scene.hpp"

#include <stdexcept>

namespace sim {

namespace {
constexpr std::array<const char*, kEffectCount> kNames = {
    "gravity", "ground_contact", "friction", "hard_limits", "self_collision", "dynamic_pins"};
}  // namespace

const char* to_string(Effect e) { return kNames[static_cast<int>(e)]; }

std::optional<Effect> effect_from_string(std::string_view name) {
  for (int k = 0; k < kEffectCount; ++k) {
    if (name == kNames[k]) return static_cast<Effect>(k);
  }
  return std::nullopt;
}

bool Scene::has(Effect e) const {
  switch (e) {
    case Effect::kGravity:
      return gravity;
    case Effect::kGroundContact:
      return ground_contact;
    case Effect::kFriction:
      return friction;
    case Effect::kHardLimits:
      return hard_limits;
    case Effect::kSelfCollision:
      return self_collision;
    case Effect::kDynamicPins:
      return dynamic_pins;
  }
  return false;
}

void Scene::set(Effect e, bool on) {
  switch (e) {
    case Effect::kGravity:
      gravity = on;
      break;
    case Effect::kGroundContact:
      ground_contact = on;
      break;
    case Effect::kFriction:
      friction = on;
      break;
    case Effect::kHardLimits:
      hard_limits = on;
      break;
    case Effect::kSelfCollision:
      self_collision = on;
      break;
    case Effect::kDynamicPins:
      dynamic_pins = on;
      break;
  }
}

bool Scene::kinematic() const {
  for (Effect e : kAllEffects) {
    if (has(e)) return false;
  }
  return true;
}

std::vector<Effect> Scene::effects() const {
  std::vector<Effect> out;
  for (Effect e : kAllEffects) {
    if (has(e)) out.push_back(e);
  }
  return out;
}

Scene Scene::from_names(const std::vector<std::string>& names) {
  Scene s;
  for (const std::string& n : names) {
    const std::optional<Effect> e = effect_from_string(n);
    if (!e) {
      std::string known;
      for (const char* k : kNames) known += std::string(known.empty() ? "" : ", ") + k;
      throw std::invalid_argument("unknown effect '" + n + "' (known: " + known + ")");
    }
    s.set(*e, true);
  }
  return s;
}

}  // namespace sim
