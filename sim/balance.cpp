#include "sim/balance.hpp"

#include <algorithm>

#include "core/com.hpp"
#include "sim/collision.hpp"
#include "sim/support_polygon.hpp"
#include "sim/world.hpp"

namespace sim {

using core::Vector3;

namespace {
constexpr double kSupportTolerance = 0.01;  // m
}

GroundReaction ground_reaction(const World& world, int body) {
  GroundReaction g;
  for (const ContactPair& p : world.contact_pairs()) {
    if (p.body != body || p.partner_body != -1) continue;  // another body's, or self contact
    const Vector3 f = p.wrench.tail<3>();
    g.force += f;
    g.moment += p.wrench.head<3>() + p.ref_W.cross(f);
  }
  return g;
}

std::optional<Vector3> center_of_pressure(const World& world, int body) {
  const GroundPlane& ground = world.environment().ground;
  const Vector3 n = ground.normal.normalized();
  double total = 0;
  Vector3 sum = Vector3::Zero();
  for (const ContactPair& p : world.contact_pairs()) {
    if (p.body != body || p.partner_body != -1) continue;
    const double fn = n.dot(p.wrench.tail<3>());
    if (!(fn > 0)) continue;
    const Vector3 o = p.ref_W - n * n.dot(p.ref_W - ground.point);
    sum += fn * (o + n.cross(p.wrench.head<3>()) / fn);
    total += fn;
  }
  if (!(total > 1e-9)) return std::nullopt;
  return Vector3(sum / total);
}

namespace {

void add_ground_contact_points(const World& world, int body, std::vector<Vector3>& points) {
  for (const ContactPoint& p : world.contact_points()) {
    if (p.key.body == body && p.key.partner_body == -1 && p.key.env == 0) points.push_back(p.p_W);
  }
}

}  // namespace

std::vector<Vector3> support_polygon_of(const World& world, int body) {
  std::vector<Vector3> points;
  add_ground_contact_points(world, body, points);
  return support_polygon(points, world.environment().ground);
}

std::vector<Vector3> standing_support_polygon(const World& world,
                                              int body,
                                              const core::Data& data) {
  std::vector<ContactPoint> near;
  find_points_near_ground(body, world.shapes(body), data, world.environment().ground, kStandingGap,
                          near);
  std::vector<Vector3> points;
  add_ground_contact_points(world, body, points);
  for (const ContactPoint& p : near) points.push_back(p.p_W);
  return support_polygon(points, world.environment().ground);
}

BalanceMeasures measure_balance(const World& world,
                                int body,
                                const core::Model& model,
                                core::Data& data) {
  const GroundPlane& ground = world.environment().ground;
  const GroundReaction g = ground_reaction(world, body);
  BalanceMeasures b;
  b.com = core::center_of_mass(model, data);
  b.cop = center_of_pressure(world, body);
  b.polygon = standing_support_polygon(world, body, data);
  b.normal_force = std::max(0.0, ground.normal.normalized().dot(g.force));
  b.com_supported = b.cop && inside_polygon(b.polygon, b.com, ground, kSupportTolerance);
  return b;
}

}  // namespace sim
