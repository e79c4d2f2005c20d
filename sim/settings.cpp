#include "sim/settings.hpp"

#include <cmath>
#include <utility>

namespace sim {

const char* to_string(Integrator i) {
  switch (i) {
    case Integrator::kImplicit:
      return "implicit";
    case Integrator::kSemiImplicit:
      return "semi_implicit";
    case Integrator::kRk4:
      return "rk4";
  }
  return "";
}

ContactSettings figure_contact_settings(double mass) {
  constexpr double g = 9.81;
  ContactSettings c;
  c.kp = 1e6;
  c.kd = 2 * 0.7 * std::sqrt(c.kp * mass / 4);
  c.mu_static = 0.8;
  c.mu_dynamic = 0.6;
  c.kfp = c.mu_static * mass * g / 2 / 0.005;
  c.kfd = 0.005 * c.kfp;
  return c;
}

std::string validate(const WorldSettings& s) {
  if (!std::isfinite(s.step) || s.step <= 0 || s.step > 0.1) {
    return "step: must be a finite number in (0, 0.1] s";
  }
  const ContactSettings& c = s.contact;
  for (const auto& [name, value] : {std::pair{"contact.kp", c.kp},
                                    {"contact.kd", c.kd},
                                    {"contact.kfp", c.kfp},
                                    {"contact.kfd", c.kfd},
                                    {"contact.mu_static", c.mu_static},
                                    {"contact.mu_dynamic", c.mu_dynamic}}) {
    if (!std::isfinite(value) || value < 0) {
      return std::string(name) + ": must be a finite number >= 0";
    }
  }
  if (c.mu_dynamic > c.mu_static) return "contact.mu_dynamic: must not exceed contact.mu_static";
  if (!std::isfinite(c.smoothing) || c.smoothing <= 0) {
    return "contact.smoothing: must be a finite number > 0";
  }
  return {};
}

}  // namespace sim
