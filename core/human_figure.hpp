// The parametric human figure: one definition that builds the 48-DOF posing figure and the
// 34-DOF HeiMan-like figure of Felis et al. (their Table I) for any stature and body mass.
//
// Segment masses, lengths, centres of mass and radii of gyration come from de Leva (1996),
// Table 4, male (Zatsiorsky–Seluyanov adjusted), scaled to the stature (de Leva's reference
// 1.741 m) and the mass. Joint ranges come from clinical range-of-motion norms (AAOS; Kapandji;
// White & Panjabi for the upper cervical spine; Inman et al. for the shoulder girdle).
// docs/human-figure.md lists every number and what was chosen where the sources are silent.
//
// Conventions: Y up, the figure faces +Z, its left is +X. Every link frame is aligned with the
// world at the neutral configuration (all joints at zero / identity), where the figure stands
// upright with the arms hanging, palms facing the thighs, the soles on y = 0 and the vertex at
// y = height. The left side is authored; the right side is its exact mirror image in the plane
// x = 0 (positions p → (−x, y, z), joint axes a → (a_x, −a_y, −a_z), so equal joint values give
// mirrored poses; twist limits of spherical ranges swap sign).
#pragma once

#include <memory>

#include "core/model.hpp"

namespace core {

/// Accepted stature (m) and body mass (kg) of the generator.
constexpr double kHumanMinHeight = 0.5;
constexpr double kHumanMaxHeight = 2.5;
constexpr double kHumanMinMass = 10.0;
constexpr double kHumanMaxMass = 300.0;

struct HumanFigureOptions {
  double height =
      1.75;          // standing height, sole to vertex (m), in [kHumanMinHeight, kHumanMaxHeight]
  double mass = 75;  // total body mass (kg), in [kHumanMinMass, kHumanMaxMass]
  int dof = 48;      // velocity DOF: 48 (posing figure) or 34 (HeiMan-like, Felis Table I)
};

/// Builds the human figure. Links (an API: other code and users refer to them by name):
///   pelvis, abdomen, chest, neck, head, l_clav, r_clav, l_uarm, r_uarm, l_farm, r_farm,
///   l_hand, r_hand, l_thigh, r_thigh, l_shank, r_shank, l_foot, r_foot, l_toes, r_toes.
/// 48 DOF: free pelvis (6); spherical abdomen, chest, neck, shoulders (l/r_uarm), wrists
///   (l/r_hand), hips (l/r_thigh), ankles (l/r_foot) (33); revolute clavicle elevation, head nod,
///   elbows, knees, toes (9).
/// 34 DOF: free pelvis; spherical abdomen (lumbar), neck, shoulders, hips, ankles; revolute
///   elbows and knees; chest, head, clavicles, hands and toes on fixed joints.
/// Model names: "human48", "human34".
/// @throws std::invalid_argument when height or mass is not finite or out of range, or dof is
///         neither 34 nor 48
std::shared_ptr<const Model> build_human_figure(const HumanFigureOptions& options = {});

}  // namespace core
