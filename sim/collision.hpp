// The contact search: which points of which links touch the environment (the ground plane and the
// static boxes) or another link of the same body, how deep, and along which normal.
//
// Broad phase: one bounding sphere per link (sim/shapes.hpp) against the plane, against each
// static box, and, for link pairs, a sort-and-sweep along x, so a standing figure costs what its
// few touching links cost. Narrow phase, several points per pair where a shape can rest:
//  - sphere: its deepest point; capsule: each end sphere (a capsule lying flat rests on two);
//  - box: each corner inside the other solid (a box lying flat rests on four);
//  - link against link: the capsule proxies' closest points (boxes as their inner capsule).
#pragma once

#include <cstdint>
#include <vector>

#include "core/data.hpp"
#include "sim/environment.hpp"
#include "sim/shapes.hpp"

namespace sim {

/// What the world knows a contact point by from one step to the next (friction anchors).
struct FeatureKey {
  int body = 0, link = 0, shape = 0, vertex = 0;
  int partner_body = -1, partner_link = 0;  // partner_body -1: the environment object `env`
  int env = 0;                              // 0: ground plane, k + 1: static box k
  bool operator==(const FeatureKey&) const = default;
};

struct ContactPoint {
  FeatureKey key;
  core::Vector3 p_W;  // the deepest point of the body's shape (on link key.link)
  core::Vector3 n_W;  // unit normal pushing that link out: from the partner toward it
  double depth = 0;   // penetration (m), > 0
};

/// Contacts of body `body` (its links' poses in data.X_W) with the environment.
void find_environment_contacts(int body,
                               const BodyShapes& shapes,
                               const core::Data& data,
                               const Environment& env,
                               std::vector<ContactPoint>& out);

/// The points of body `body`'s shapes (as find_environment_contacts finds them on the ground)
/// that lie less than `gap` (m) above the ground plane or in it: the points in contact and those
/// about to be. Their depth is negative above the plane.
void find_points_near_ground(int body,
                             const BodyShapes& shapes,
                             const core::Data& data,
                             const GroundPlane& ground,
                             double gap,
                             std::vector<ContactPoint>& out);

/// Contacts between links of one body. `order` is scratch space that keeps the sweep's sorted
/// order from one step to the next (nearly sorted input sorts in linear time).
void find_self_contacts(int body,
                        const BodyShapes& shapes,
                        const core::Data& data,
                        std::vector<int>& order,
                        std::vector<ContactPoint>& out);

}  // namespace sim
