// Swing–twist parameterization of spherical joint rotations and the triangle-patch range test
// (Yamane §8.3.5, digest §2.5).
//
// A rotation q, expressed in a range frame whose x axis is the nominal link direction, factors
// as q = q_swing ⊗ q_twist: first a twist γ about x, then a swing about an axis in the y–z plane.
// a = (a_y, a_z) is the vector part of q_swing, so |a| = sin(φ/2) for swing angle φ
// (Yamane eqs. 8.28–8.29). The factorization is singular only at φ = π (R(1,1) = −1).
#pragma once

#include <vector>

#include "core/model.hpp"

namespace core {

struct SwingTwist {
  double a_y = 0;
  double a_z = 0;
  double twist = 0;       // γ in (−π, π]
  bool singular = false;  // swing within 1e-9 of π: twist and swing axis are undefined
};

/// Swing–twist of a rotation given in range-frame coordinates. Sign-invariant (q and −q agree).
SwingTwist swing_twist(const Quaternion& q);
/// Inverse of swing_twist: q_swing(a) ⊗ q_twist(γ); requires |a| <= 1.
Quaternion from_swing_twist(double a_y, double a_z, double twist);
/// Swing–twist of spherical joint i for its joint rotation q_joint (joint-frame coordinates).
SwingTwist joint_swing_twist(const Model& model, int i, const Quaternion& q_joint);

/// Swing vector that tilts the nominal direction (x) by angle phi toward (0, cos ψ, sin ψ).
Eigen::Vector2d swing_toward(double psi, double phi);

struct RangeStatus {
  bool inside = true;
  int triangle = -1;       // a triangle containing the swing, or -1 when the swing is outside
  double twist_lower = 0;  // interpolated twist limits in that triangle
  double twist_upper = 0;
  double violation = 0;  // how far outside the range (rad, 0 inside): swing or twist excess
};

/// The range test of Yamane §8.3.5: the swing must lie in a triangle, and the twist between the
/// limits interpolated barycentrically from the triangle's vertices. A twist is accepted modulo
/// 2π, so limits may straddle ±π. An empty range accepts everything.
RangeStatus check_range(const SphericalRange& range, const SwingTwist& st);

/// The inner bounds of a range (see RangeInnerBounds): the largest disk around the nominal
/// direction inside the triangles, and the twist interval every vertex allows.
RangeInnerBounds inner_bounds(const SphericalRange& range);

/// check_range for spherical joint i of a model, answering from the inner bounds when they
/// suffice (the common case of a joint well inside its range).
RangeStatus check_joint_range(const Model& model, int i, const SwingTwist& st);
/// True when spherical joint i's rotation q_joint is inside its range by the inner bounds alone,
/// without the swing–twist factorization (RangeInnerBounds::rotation_sin_half); false means
/// "not known": check_joint_range decides.
bool joint_rotation_surely_inside(const Model& model, int i, const Quaternion& q_joint);
/// The range test of spherical joint i for its joint rotation q_joint: the quick test above
/// first, then the swing–twist factorization and check_joint_range when it cannot tell.
RangeStatus joint_range_status(const Model& model, int i, const Quaternion& q_joint);

/// A cone of half-angle swing_max around the nominal direction with a constant twist interval,
/// authored as a triangle fan of `segments` triangles.
SphericalRange cone_range(double swing_max,
                          double twist_lower,
                          double twist_upper,
                          int segments = 12);

/// A fan whose swing limit varies with the tilt direction: swing_max[k] toward direction
/// psi[k] (psi increasing, covering the full circle), twist limits per rim vertex and at the
/// nominal direction (the fan's centre).
SphericalRange directional_range(const std::vector<double>& psi,
                                 const std::vector<double>& swing_max,
                                 const std::vector<double>& twist_lower,
                                 const std::vector<double>& twist_upper,
                                 double centre_twist_lower,
                                 double centre_twist_upper);

}  // namespace core
