#include "sim/collision.hpp"

#include <algorithm>
#include <cmath>

#include "sim/geometry.hpp"

namespace sim {

namespace {

using core::Transform;
using core::Vector3;

const std::array<Vector3, 8> kCorners = {
    Vector3(-1, -1, -1), Vector3(1, -1, -1), Vector3(-1, 1, -1), Vector3(1, 1, -1),
    Vector3(-1, -1, 1),  Vector3(1, -1, 1),  Vector3(-1, 1, 1),  Vector3(1, 1, 1)};

// the spheres a shape rests on: a sphere's own, a capsule's two ends
int shape_spheres(const LinkShape& s, const Transform& X_WS, std::array<Vector3, 2>& centers) {
  if (s.kind == LinkShape::Kind::kSphere) {
    centers[0] = X_WS.p;
    return 1;
  }
  const Vector3 d = X_WS.R.col(2) * s.half_length;
  centers[0] = X_WS.p - d;
  centers[1] = X_WS.p + d;
  return 2;
}

void push(std::vector<ContactPoint>& out,
          const FeatureKey& key,
          const Vector3& p,
          const Vector3& n,
          double depth) {
  out.push_back({key, p, n, depth});
}

// one shape against the ground plane: the points deeper than −gap (gap 0: in contact)
void shape_on_plane(const LinkShape& s,
                    const Transform& X_WS,
                    const GroundPlane& g,
                    FeatureKey key,
                    std::vector<ContactPoint>& out,
                    double gap) {
  if (s.kind == LinkShape::Kind::kBox) {
    for (int c = 0; c < 8; ++c) {
      const Vector3 x = X_WS * kCorners[c].cwiseProduct(s.half_extents);
      const double depth = -g.normal.dot(x - g.point);
      key.vertex = c;
      if (depth > -gap) push(out, key, x, g.normal, depth);
    }
    return;
  }
  std::array<Vector3, 2> centers;
  const int n = shape_spheres(s, X_WS, centers);
  for (int c = 0; c < n; ++c) {
    const double depth = s.radius - g.normal.dot(centers[c] - g.point);
    key.vertex = c;
    if (depth > -gap) push(out, key, centers[c] - s.radius * g.normal, g.normal, depth);
  }
}

// a sphere of radius r at c against a static box
void sphere_on_box(const Vector3& c,
                   double r,
                   const StaticBox& box,
                   const FeatureKey& key,
                   std::vector<ContactPoint>& out) {
  const BoxQuery b = query_box(box.pose, box.half_extents, c);
  if (b.inside) {
    push(out, key, c - r * b.face_normal_W, b.face_normal_W, r + b.face_depth);
    return;
  }
  const Vector3 d = c - b.closest_W;
  const double dist = d.norm();
  if (dist >= r || dist == 0) return;
  const Vector3 n = d / dist;
  push(out, key, c - r * n, n, r - dist);
}

// one shape against a static box
void shape_on_box(const LinkShape& s,
                  const Transform& X_WS,
                  const StaticBox& box,
                  FeatureKey key,
                  std::vector<ContactPoint>& out) {
  if (s.kind == LinkShape::Kind::kBox) {
    for (int c = 0; c < 8; ++c) {
      const Vector3 x = X_WS * kCorners[c].cwiseProduct(s.half_extents);
      const BoxQuery b = query_box(box.pose, box.half_extents, x);
      key.vertex = c;
      if (b.inside) push(out, key, x, b.face_normal_W, b.face_depth);
    }
    return;
  }
  std::array<Vector3, 2> centers;
  const int n = shape_spheres(s, X_WS, centers);
  for (int c = 0; c < n; ++c) {
    key.vertex = c;
    sphere_on_box(centers[c], s.radius, box, key, out);
  }
  if (n == 2) {
    // a capsule across a box edge touches it between its ends: the segment point closest to the
    // box, found by alternating projections (both sets are convex)
    Vector3 on_seg = X_WS.p, on_box;
    for (int it = 0; it < 4; ++it) {
      on_box = query_box(box.pose, box.half_extents, on_seg).closest_W;
      Vector3 unused;
      segment_closest_points(centers[0], centers[1], on_box, on_box, on_seg, unused);
    }
    const double t = (on_seg - centers[0]).dot(centers[1] - centers[0]) /
                     std::max(1e-300, (centers[1] - centers[0]).squaredNorm());
    if (t > 0.05 && t < 0.95) {
      key.vertex = 2;
      sphere_on_box(on_seg, s.radius, box, key, out);
    }
  }
}

// the world-space bounding sphere of a link
bool link_sphere(
    const BodyShapes& shapes, const core::Data& data, int link, Vector3& c, double& r) {
  const LinkBound& b = shapes.bounds[link];
  if (b.radius < 0) return false;
  c = data.X_W[link] * b.center_Link;
  r = b.radius;
  return true;
}

// link i's shapes against the ground plane, the points deeper than −gap; (c, r) its bounding
// sphere (link_sphere) tells first whether any can be
void link_on_plane(int body,
                   int i,
                   const BodyShapes& shapes,
                   const core::Data& data,
                   const GroundPlane& g,
                   const Vector3& c,
                   double r,
                   double gap,
                   std::vector<ContactPoint>& out) {
  if (g.normal.dot(c - g.point) >= r + gap) return;
  for (const LinkShape& s : shapes.shapes[i]) {
    shape_on_plane(s, data.X_W[i] * s.X_LinkShape, g, FeatureKey{body, i, s.index, 0, -1, 0, 0},
                   out, gap);
  }
}

}  // namespace

void find_environment_contacts(int body,
                               const BodyShapes& shapes,
                               const core::Data& data,
                               const Environment& env,
                               std::vector<ContactPoint>& out) {
  const int njoints = static_cast<int>(shapes.shapes.size());
  for (int i = 1; i < njoints; ++i) {
    Vector3 c;
    double r;
    if (!link_sphere(shapes, data, i, c, r)) continue;
    // a link's ground points before its box points: group_into_pairs' stable sort by pair keeps
    // each pair's points in shape order either way
    link_on_plane(body, i, shapes, data, env.ground, c, r, 0.0, out);
    for (int k = 0; k < static_cast<int>(env.boxes.size()); ++k) {
      const StaticBox& box = env.boxes[k];
      const BoxQuery q = query_box(box.pose, box.half_extents, c);
      if (!q.inside && (c - q.closest_W).squaredNorm() >= r * r) continue;
      for (const LinkShape& s : shapes.shapes[i]) {
        shape_on_box(s, data.X_W[i] * s.X_LinkShape, box,
                     FeatureKey{body, i, s.index, 0, -1, 0, k + 1}, out);
      }
    }
  }
}

void find_points_near_ground(int body,
                             const BodyShapes& shapes,
                             const core::Data& data,
                             const GroundPlane& ground,
                             double gap,
                             std::vector<ContactPoint>& out) {
  const int njoints = static_cast<int>(shapes.shapes.size());
  for (int i = 1; i < njoints; ++i) {
    Vector3 c;
    double r;
    if (link_sphere(shapes, data, i, c, r))
      link_on_plane(body, i, shapes, data, ground, c, r, gap, out);
  }
}

void find_self_contacts(int body,
                        const BodyShapes& shapes,
                        const core::Data& data,
                        std::vector<int>& order,
                        std::vector<ContactPoint>& out) {
  if (shapes.self_pairs.empty()) return;
  const int njoints = static_cast<int>(shapes.shapes.size());
  // sort-and-sweep along x over the links' bounding spheres
  if (static_cast<int>(order.size()) != njoints - 1) {
    order.clear();
    for (int i = 1; i < njoints; ++i) order.push_back(i);
  }
  auto lo = [&](int i) {
    const LinkBound& b = shapes.bounds[i];
    return b.radius < 0 ? std::numeric_limits<double>::infinity()
                        : (data.X_W[i] * b.center_Link).x() - b.radius;
  };
  // insertion sort: the order changes little between steps
  for (size_t a = 1; a < order.size(); ++a) {
    const int v = order[a];
    const double key = lo(v);
    size_t b = a;
    for (; b > 0 && lo(order[b - 1]) > key; --b) order[b] = order[b - 1];
    order[b] = v;
  }
  for (size_t a = 0; a < order.size(); ++a) {
    const int i = order[a];
    Vector3 ci;
    double ri;
    if (!link_sphere(shapes, data, i, ci, ri)) break;  // the rest have no shapes
    for (size_t b = a + 1; b < order.size(); ++b) {
      const int j = order[b];
      Vector3 cj;
      double rj;
      if (!link_sphere(shapes, data, j, cj, rj) || cj.x() - rj > ci.x() + ri) break;
      if ((ci - cj).squaredNorm() >= (ri + rj) * (ri + rj)) continue;
      const std::pair<int, int> pair(std::min(i, j), std::max(i, j));
      if (!std::binary_search(shapes.self_pairs.begin(), shapes.self_pairs.end(), pair)) continue;
      // the link with the larger index is the one pushed along the normal
      const int lb = pair.second, la = pair.first;
      for (const LinkShape& sb : shapes.shapes[lb]) {
        const CapsuleProxy pb = capsule_proxy(sb, data.X_W[lb]);
        for (const LinkShape& sa : shapes.shapes[la]) {
          const CapsuleProxy pa = capsule_proxy(sa, data.X_W[la]);
          Vector3 on_b, on_a;
          const double d2 = segment_closest_points(pb.a_W, pb.b_W, pa.a_W, pa.b_W, on_b, on_a);
          const double rr = pa.radius + pb.radius;
          if (d2 >= rr * rr || d2 == 0) continue;
          const double dist = std::sqrt(d2);
          const Vector3 n = (on_b - on_a) / dist;
          push(out, {body, lb, sb.index, 0, body, la, sa.index}, on_b - pb.radius * n, n,
               rr - dist);
        }
      }
    }
  }
}

}  // namespace sim
