// The force at one soft contact point and its derivatives (Yamane §6.3, digest §2.13 with the
// corrections of reference/digest-check.md).
//
// Normal (eq. 6.14): f_z = (kP d − kD u) / n_C, d the penetration, u the normal speed (positive
// separating). A pair never pulls: when kP d − kD u < 0 the point carries no force at all.
// Static friction (eq. 6.16, restoring sign): a spring and damper to the anchor p̂ where the
// point first touched, f̂ = (−kFP (p − p̂)_t − kFD s) / n_C.
// Dynamic friction (eqs. 6.17–6.18): f = −μD f_z w(|s|) s / |s| with w(x) = 1 − exp(−k x); the
// anchor then follows the point (p̂ = p) until the static force fits again.
//
// Which of the two acts is decided per pair, not per point as in the book: the pair sticks while
// its total static force fits its total cone, |Σ f̂_k| <= μS Σ f_z,k. The points of one pair
// belong to one rigid link on one surface; judged one by one, a box on a slope loses the corners
// its tipping moment unloads, then the rest, and creeps where Coulomb says it holds.
//
// w's rate k is at least the book's c / h, and steep enough that w is nearly 1 at the slip speed
// below which the pair's static force fits again (kFD s <= μS F_z): a gentler w would let a load
// just under μD F_z creep forever at a speed static friction never catches.
//
// All forces act on the body's point; its partner (when it is a link) receives the opposite.
// Derivatives are taken with respect to the point's displacement and velocity relative to the
// partner, world axes, with the pair's total normal force (which sets k) held fixed; the 1/n_C of
// the force law is kept in them (the book prints it only in the forces).
#pragma once

#include "core/spatial.hpp"
#include "sim/settings.hpp"

namespace sim {

struct PointState {
  core::Vector3 position_W;      // the contact point
  core::Vector3 normal_W;        // unit, pushing the point out
  core::Vector3 velocity_W;      // of the point relative to its partner
  double depth = 0;              // penetration (m)
  core::Vector3 anchor_W;        // static-friction anchor p̂
  int points_in_pair = 1;        // n_C
  double pair_normal_force = 0;  // Σ f_z over the pair (N); sets w's rate k
};

/// The normal force and the static-friction trial of a point, before its pair decides.
struct Trial {
  double normal = 0;                               // f_z (N), 0 when separating
  core::Vector3 friction = core::Vector3::Zero();  // f̂ (N)
};
Trial trial_forces(const PointState& s, const ContactSettings& c);

enum class FrictionState { kOff, kStick, kSlide };

/// The friction state of a pair from its points' trials: stick while |Σ f̂| <= μS Σ f_z.
FrictionState pair_friction(const Trial* trials, int count, const ContactSettings& c);

struct PointForce {
  core::Vector3 force_W = core::Vector3::Zero();   // on the point
  core::Matrix3 dF_dp = core::Matrix3::Zero();     // ∂f/∂p (relative displacement)
  core::Matrix3 dF_dv = core::Matrix3::Zero();     // ∂f/∂ṗ (relative velocity)
  core::Vector3 anchor_W = core::Vector3::Zero();  // the anchor to keep for the next step
  double normal_force = 0;                         // f_z (N)
};

/// The point's force in the friction state its pair chose; `h` is the step (for k).
PointForce point_force(const PointState& s,
                       const ContactSettings& c,
                       FrictionState friction,
                       double h);

}  // namespace sim
