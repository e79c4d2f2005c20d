// Balance feedback for a figure whose joints are driven by the dynamics-backed pins: it keeps the
// capture point over the support by moving the centre of pressure, the way a standing person uses
// the ankles. Nothing pushes the figure but the ground: the feedback only changes the
// orientation targets of the pins on the links that stand on the ground (a foot pinned flat), so
// that the joints tilt them by the fraction of a milliradian that moves their pressure where it
// is wanted; the soft contact turns that tilt into the moment.
//
// Capture point (divergent component of motion) of the linear inverted pendulum:
//     ξ = c + ċ / ω₀,  ω₀ = √(g / z_c),  ξ̇ = ω₀ (ξ − p)
// for the centre of mass c at height z_c over the ground and the centre of pressure p. Asking
// ξ̇ = −k (ξ − ξ_ref), with ξ_ref the mean of the supporting links' footprints (each the centroid
// of its contact points when last loaded: a foot that lifts for a moment does not move the
// reference onto the other, which would tip the figure further that way), gives the desired CoP
//     p_d = ξ + (k / ω₀) (ξ − ξ_ref),
// kept a margin inside the support polygon. Each supporting link's own CoP is moved by the same
// p_d − p (clamped to its own contact points), which changes the ground's moment on it about its
// reference point by ΔM = (c_d − c) × F n. A small tilt δ of a link in soft contact changes that
// moment by −K δ with K = Σ_k (k_P / n_C) u_k u_kᵀ, u_k = r_k × n over its points (r_k from the
// reference point; from eq. 6.14), so the link's target is its present tilt from the pin's own
// orientation plus δ = −K⁻¹ ΔM, and the pin's feedback law tilts it there. A link standing on an
// edge or a corner is sent back to the pin's orientation (flat) instead.
#pragma once

#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"
#include "ik/problem.hpp"
#include "sim/environment.hpp"
#include "sim/settings.hpp"

namespace sim {

class World;

struct BalanceSettings {
  bool enabled = true;
  double frequency = 2.0;  // k (1/s): the capture point's error decays as exp(−k t)
  double margin = 0.02;    // m: the desired CoP stays this far inside the support polygon
  double max_tilt = 0.02;  // rad: the largest tilt of a supporting link from its pin's orientation
  // ω (rad/s) of the pins on supporting links while the feedback tilts them: the CoP must follow
  // faster than the capture point diverges (ω₀ ≈ 3 rad/s for a standing adult)
  double support_frequency = 40.0;
  bool operator==(const BalanceSettings&) const = default;
};

/// Empty when usable, else a message naming the first bad field.
std::string validate(const BalanceSettings& s);

struct BalanceState {
  bool active = false;  // in ground contact with at least one pinned supporting link
  int supports = 0;     // pinned links in ground contact the feedback tilts
  core::Vector3 capture_point = core::Vector3::Zero();  // ξ, on the ground
  core::Vector3 desired_cop = core::Vector3::Zero();    // p_d
  core::Vector3 cop = core::Vector3::Zero();            // p, at the step's start
};

class BalanceFeedback {
 public:
  /// Copies `problem` into `solved` and turns the orientation targets of its pins on supporting
  /// links as above. Requires: the step's kinematics and joint Jacobians of body b in `data`, its
  /// contact wrenches in the world's pairs.
  const BalanceState& update(const World& world,
                             int body,
                             const core::Model& model,
                             core::Data& data,
                             const Eigen::VectorXd& v,
                             const BalanceSettings& settings,
                             const ik::Problem& problem,
                             ik::Problem& solved);
  const BalanceState& state() const { return state_; }

 private:
  struct Footprint {
    int link = 0;
    core::Vector3 centre = core::Vector3::Zero();
    bool seen = false;  // still a supporting pin in this step
  };
  struct Support {
    int entry = 0, pair = 0;  // the pin in the solved problem, its ground pair
    core::Vector3 footprint = core::Vector3::Zero();
    std::vector<core::Vector3> polygon;         // its own contact points' hull
    bool flat = false;                          // the hull has an area (not an edge, not a corner)
    double force = 0;                           // N, normal, now
    core::Vector3 cop = core::Vector3::Zero();  // its own, now
    double wanted_force = 0;
    core::Vector3 wanted_cop = core::Vector3::Zero();
  };
  const core::Vector3& remember_footprint(int link, const core::Vector3& centre);
  core::Vector3 footprint_of(int link, const core::Vector3& fallback) const;
  double supported_load(const World& world,
                        int body,
                        const core::Model& model,
                        const core::Vector3& n) const;
  void distribute_load(const core::Vector3& cop, double total, const GroundPlane& ground);
  core::Vector3 reference(const core::Vector3& fallback);

  BalanceState state_;
  std::vector<core::Vector3> points_, polygon_;
  std::vector<Footprint> footprints_;
  std::vector<Support> supports_;
};

}  // namespace sim
