// Settings of a simulated world: the fixed step, the integrator and the soft-contact parameters
// (Yamane §6.3.6 and §6.4 give the defaults).
#pragma once

#include <string>

namespace sim {

enum class Integrator {
  kImplicit,      // linearized backward Euler in contact space (Yamane eq. 6.6), else semi-implicit
  kSemiImplicit,  // symplectic Euler: v += h a(q, v); q ⊕= h v
  kRk4,           // classical Runge–Kutta on (q, v), contact forces explicit at every stage
};
const char* to_string(Integrator i);

/// Soft contact (Yamane §6.3). Forces per point are divided by the number of points of their
/// pair, so a pair's total force does not depend on how many points it has.
struct ContactSettings {
  double kp = 1e5;          // normal stiffness (N/m), f_z = (kp d − kd u) / n_C (eq. 6.14)
  double kd = 1e3;          // normal damping (N s/m)
  double mu_static = 0.5;   // μS: static friction holds while |f_t| <= μS f_z
  double mu_dynamic = 0.4;  // μD: sliding friction μD f_z w(|s|) (eq. 6.17)
  double kfp = 2000;        // static-friction anchor spring (N/m), eq. 6.16
  double kfd = 1400;        // static-friction damper (N s/m)
  double smoothing = 0.1;   // c of w(x) = 1 − exp(−(c / h) x) (eq. 6.18; the book uses 0.1)
  bool operator==(const ContactSettings&) const = default;
};

struct WorldSettings {
  double step = 1e-3;  // fixed physics step h (s)
  Integrator integrator = Integrator::kImplicit;
  ContactSettings contact;
  bool operator==(const WorldSettings&) const = default;
};

/// Empty when usable, else a message naming the first bad field ("contact.kp: must be ...").
std::string validate(const WorldSettings& s);

/// Contact for a figure of `mass` kg standing on its feet (two feet, each a foot and a toe pair):
/// k_P = 1e6 (a stiff sole: at 1e5 a figure whose centre of mass is a few cm in front of its heels
/// tilts back onto them and topples, since each pair carries the same stiffness however small),
/// k_D for a damping ratio of 0.7 with a quarter of the weight on each pair, μS 0.8 and μD 0.6
/// (rubber on wood), the static-friction anchor stretched 5 mm under μS m g / 2, and k_FD small
/// enough for the explicit contact forces of dynamics-backed pins: h k_FD / m_eff < 1 at 1 ms
/// for the few kilograms a foot weighs once the body above can rotate (Yamane §6.3.6 leaves
/// k_FP and k_FD to the model).
ContactSettings figure_contact_settings(double mass);

}  // namespace sim
