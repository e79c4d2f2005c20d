// Balance measures of a body standing on the ground plane: the ground's push on it (total force
// and moment), its centre of pressure, its support polygon and whether its centre of mass
// projects inside that polygon. Read by `pindrag solve`, the page and the balance feedback of the
// dynamics-backed pins.
#pragma once

#include <optional>
#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"
#include "core/spatial.hpp"
#include "sim/environment.hpp"

namespace sim {

class World;

/// The ground plane's push on body b: total force and moment about the world origin.
struct GroundReaction {
  core::Vector3 force = core::Vector3::Zero();
  core::Vector3 moment = core::Vector3::Zero();
};
GroundReaction ground_reaction(const World& world, int body);

/// The centre of pressure of body b on the ground plane: the mean of its ground pairs' own centres
/// of pressure weighted by their normal forces. A pair's is c = o + n × M / (n · F), with o its
/// reference point projected onto the plane and M its moment about the reference (for n = +y:
/// c_x = o_x + M_z / F_y, c_z = o_z − M_x / F_y). Taken pair by pair, the friction of points a
/// millimetre deep does not shift it off the contact points as one moment about a point of the
/// plane would. Empty when nothing presses on the ground.
std::optional<core::Vector3> center_of_pressure(const World& world, int body);

/// The convex hull of body b's contact points with the ground plane, on the plane: where the
/// ground can push on it in this step (the balance feedback's bound on the centre of pressure).
std::vector<core::Vector3> support_polygon_of(const World& world, int body);

/// How far above the ground (m) a point of a body's shapes still counts as standing on it. A
/// lightly loaded foot in soft contact (1e6 N/m per point) rises out of the ground and sinks back
/// by a fraction of a millimetre from one step to the next while the figure stands still; a foot
/// lifted to step clears the ground by centimetres.
inline constexpr double kStandingGap = 0.002;

/// The convex hull, on the ground plane, of body b's contact points with the ground and of the
/// points of its shapes in the ground or less than kStandingGap above it (links' poses in `data`):
/// the support of the figure standing, which a foot that unloads for a moment does not take away.
/// It holds support_polygon_of (the contacts found at the start of the last step) whatever
/// configuration `data` holds.
std::vector<core::Vector3> standing_support_polygon(const World& world,
                                                    int body,
                                                    const core::Data& data);

struct BalanceMeasures {
  core::Vector3 com = core::Vector3::Zero();
  std::optional<core::Vector3> cop;  // empty when not pressing on the ground
  // the standing support polygon (fewer than 3 points: a point, a line)
  std::vector<core::Vector3> polygon;
  double normal_force = 0;  // N, along the ground's normal, never negative
  /// The centre of mass projects inside the support polygon (within 1 cm). False in the air.
  bool com_supported = false;
};

/// Balance measures of body b; `data` holds its kinematics (core::forward_kinematics) already, for
/// the body's present configuration; its centre-of-mass fields are updated.
BalanceMeasures measure_balance(const World& world,
                                int body,
                                const core::Model& model,
                                core::Data& data);

}  // namespace sim
