#include "server/thumbnail_scene.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/bounds.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"

namespace server {

namespace {

using core::Vector3;

std::string index_text(const std::string& field, std::size_t i) {
  return field + "[" + std::to_string(i) + "]";
}

bool finite(const Eigen::Vector3f& v) { return v.allFinite(); }

// sRGB byte → linear intensity (IEC 61966-2-1)
float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}
Eigen::Vector3f linear_colour(int r, int g, int b) {
  return {srgb_to_linear(r / 255.0f), srgb_to_linear(g / 255.0f), srgb_to_linear(b / 255.0f)};
}

// figure colours (sRGB): the figure's left side cool, its right side warm, the middle neutral
const Eigen::Vector3f kLeftColour = linear_colour(0x5E, 0x8F, 0xD6);
const Eigen::Vector3f kRightColour = linear_colour(0xE5, 0x8A, 0x4E);
const Eigen::Vector3f kMiddleColour = linear_colour(0xA9, 0xAE, 0xB8);

// which side of the figure a point at the neutral configuration is on
struct SideTint {
  double centre_x = 0;
  double margin = 0;
  const Eigen::Vector3f& colour(const Vector3& p_neutral_W) const {
    if (p_neutral_W.x() > centre_x + margin) return kLeftColour;
    if (p_neutral_W.x() < centre_x - margin) return kRightColour;
    return kMiddleColour;
  }
};

void append_shapes(const core::Model& model,
                   const core::Data& posed,
                   const core::Data& neutral,
                   const Vector3& origin_W,
                   const SideTint& tint,
                   double bone_radius,
                   io::TriangleMesh& mesh) {
  const core::Transform X_FW = core::Transform::from_translation(-origin_W);
  for (int i = 1; i < model.njoints; ++i) {
    if (const auto* shapes = io::primitive_shapes(model, i)) {
      for (const core::Geometry& g : *shapes) {
        const Vector3 centre_neutral_W = neutral.X_W[i] * g.X_LinkShape.p;
        io::append_geometry(mesh, X_FW * posed.X_W[i] * g.X_LinkShape, g,
                            tint.colour(centre_neutral_W));
      }
      continue;
    }
    // no primitive: a joint ball and a bone from the parent's origin
    const Vector3 p_F = posed.X_W[i].p - origin_W;
    const int parent = model.parent[i];
    const Vector3 mid_neutral_W =
        parent > 0 ? Vector3(0.5 * (neutral.X_W[i].p + neutral.X_W[parent].p)) : neutral.X_W[i].p;
    const Eigen::Vector3f& colour = tint.colour(mid_neutral_W);
    io::append_sphere(mesh, p_F, 1.6 * bone_radius, colour);
    if (parent > 0)
      io::append_segment(mesh, posed.X_W[parent].p - origin_W, p_F, bone_radius, colour);
  }
}

void append_skin(const core::SkinnedMesh& skin,
                 const std::vector<Vector3>& p_W,
                 const std::vector<core::Transform>& X_skin,
                 const Vector3& origin_W,
                 const std::vector<Eigen::Vector3f>& bone_tint,
                 io::TriangleMesh& mesh) {
  const std::size_t n = p_W.size();
  std::vector<Vector3> normals(n, Vector3::Zero());
  if (!skin.normals.empty()) {
    // the blended rotation turns the bind normal
    for (std::size_t v = 0; v < n; ++v) {
      const auto& w = skin.weights[v];
      core::Matrix3 R = core::Matrix3::Zero();
      for (int k = 0; k < 4; ++k) R += double{w[k]} * X_skin[skin.joints[v][k]].R;
      normals[v] = R * skin.normals[v].cast<double>();
    }
  } else {
    // smooth normals of the posed surface: area-weighted face normals summed at the vertices
    for (const auto& t : skin.triangles) {
      const Vector3 face = (p_W[t[1]] - p_W[t[0]]).cross(p_W[t[2]] - p_W[t[0]]);
      for (int k = 0; k < 3; ++k) normals[t[k]] += face;
    }
  }
  // the skin's own colour, half mixed with the side tint of its bones (blended by weight)
  const Eigen::Vector3f base = skin.base_color.head<3>().cwiseMax(0.0f).cwiseMin(1.0f);
  mesh.vertices.reserve(n * io::TriangleMesh::kFloatsPerVertex);
  for (std::size_t v = 0; v < n; ++v) {
    const double length = normals[v].norm();
    const Vector3 unit = length > 0 ? Vector3(normals[v] / length) : Vector3::UnitY();
    const auto& w = skin.weights[v];
    Eigen::Vector3f tint = Eigen::Vector3f::Zero();
    for (int k = 0; k < 4; ++k) tint += w[k] * bone_tint[skin.joints[v][k]];
    tint /= w[0] + w[1] + w[2] + w[3];
    mesh.add_vertex((p_W[v] - origin_W).cast<float>(), unit.cast<float>(), 0.5f * (base + tint));
  }
  mesh.indices.reserve(skin.triangles.size() * 3);
  for (const auto& t : skin.triangles)
    mesh.add_triangle(static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]),
                      static_cast<std::uint32_t>(t[2]));
}

// a round number (1, 2 or 5 times a power of ten) close to x
double nice_step(double x) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  const double m = x / decade;
  return decade * (m < 1.5 ? 1.0 : m < 3.5 ? 2.0 : m < 7.5 ? 5.0 : 10.0);
}

// Camera framing. In camera axes (right, up, forward) a box corner c relative to the target is
// (x, y, z); the camera sits at target + a·right + b·up − d·forward, so the corner projects to
// ndc_y = (y − b) / ((z + d) tan(fov/2)), likewise x with a. For a distance d, the offsets a and b
// that centre the projected box are found by bisection (the sum of the extreme ndc values falls
// monotonically with the offset); the distance that gives the wanted extent likewise (the extent
// falls monotonically with d).
struct Framing {
  double d = 1, a = 0, b = 0;
};

struct CornerSet {
  std::vector<Vector3> c;  // camera axes, relative to the target
  double min_z = 0, max_z = 0;
};

// ndc extent along axis (0: x, 1: y) for offset o and distance d: {min, max}
std::pair<double, double> ndc_range(const CornerSet& s, int axis, double o, double d, double t) {
  double lo = 1e300, hi = -1e300;
  for (const Vector3& c : s.c) {
    const double v = (c[axis] - o) / ((c.z() + d) * t);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  return {lo, hi};
}

double centring_offset(const CornerSet& s, int axis, double d, double t, double reach) {
  double lo = -reach, hi = reach;
  for (int it = 0; it < 80; ++it) {
    const double mid = 0.5 * (lo + hi);
    const auto [a, b] = ndc_range(s, axis, mid, d, t);
    if (a + b > 0)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

// the distance at which the centred extent along `axis` is `extent` (in ndc units, 2 = full)
double fitting_distance(const CornerSet& s, int axis, double extent, double t, double reach) {
  double lo = -s.min_z + 1e-6 * reach, hi = 1e4 * reach;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    const double o = centring_offset(s, axis, mid, t, reach);
    const auto [a, b] = ndc_range(s, axis, o, mid, t);
    if (b - a > extent)
      lo = mid;
    else
      hi = mid;
  }
  return hi;
}

Eigen::Matrix4f perspective(double fov_y, double near, double far) {
  const double f = 1.0 / std::tan(0.5 * fov_y);
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = f;
  P(1, 1) = f;
  P(2, 2) = (far + near) / (near - far);
  P(2, 3) = 2 * far * near / (near - far);
  P(3, 2) = -1;
  return P.cast<float>();
}

}  // namespace

void check_thumbnail_size(int size) {
  if (size < kThumbnailMinSize || size > kThumbnailMaxSize)
    throw std::invalid_argument("options.size: " + std::to_string(size) + " is outside [" +
                                std::to_string(kThumbnailMinSize) + ", " +
                                std::to_string(kThumbnailMaxSize) + "]");
}

Eigen::VectorXd checked_configuration(const core::Model& model, const Eigen::VectorXd& q) {
  if (q.size() != model.nq)
    throw std::invalid_argument("q: size " + std::to_string(q.size()) +
                                " does not match the model's nq = " + std::to_string(model.nq));
  Eigen::VectorXd out = q;
  for (int i = 1; i < model.njoints; ++i) {
    const int first = model.idx_q[i], n = core::joint_nq(model.joint_type[i]);
    for (int k = first; k < first + n; ++k) {
      if (!std::isfinite(q[k]))
        throw std::invalid_argument(index_text("q", k) + ": not finite (joint '" +
                                    model.joint_name[i] + "')");
    }
    const core::JointType type = model.joint_type[i];
    if (type != core::JointType::kSpherical && type != core::JointType::kFree) continue;
    const int at = type == core::JointType::kFree ? first + 3 : first;
    const double norm = q.segment<4>(at).norm();
    if (!(norm > 1e-12) || !std::isfinite(norm))
      throw std::invalid_argument("q[" + std::to_string(at) + ".." + std::to_string(at + 3) +
                                  "]: zero quaternion (joint '" + model.joint_name[i] + "')");
    out.segment<4>(at) /= norm;
  }
  return out;
}

void check_skin(const core::Model& model, const core::SkinnedMesh& skin) {
  const std::size_t n = skin.positions.size();
  auto size_rule = [&](const std::string& field, std::size_t size, const std::string& rule) {
    throw std::invalid_argument("skin." + field + ": " + std::to_string(size) + " entries, " +
                                rule);
  };
  if (!skin.normals.empty() && skin.normals.size() != n)
    size_rule("normals", skin.normals.size(),
              "expected 0 or one per position (" + std::to_string(n) + ")");
  if (skin.joints.size() != n)
    size_rule("joints", skin.joints.size(),
              "expected one per position (" + std::to_string(n) + ")");
  if (skin.weights.size() != n)
    size_rule("weights", skin.weights.size(),
              "expected one per position (" + std::to_string(n) + ")");
  if (skin.inverse_bind.size() != skin.bones.size())
    size_rule("inverse_bind", skin.inverse_bind.size(),
              "expected one per bone (" + std::to_string(skin.bones.size()) + ")");
  if (n > std::size_t{0xFFFFFFFF}) size_rule("positions", n, "too many for 32-bit indices");
  for (std::size_t v = 0; v < n; ++v) {
    if (!finite(skin.positions[v]))
      throw std::invalid_argument(index_text("skin.positions", v) + ": not finite");
    if (!skin.normals.empty() && !finite(skin.normals[v]))
      throw std::invalid_argument(index_text("skin.normals", v) + ": not finite");
    double total = 0;
    for (int k = 0; k < 4; ++k) {
      const float w = skin.weights[v][k];
      if (!std::isfinite(w) || w < 0)
        throw std::invalid_argument(index_text("skin.weights", v) + ": weight " +
                                    std::to_string(w) + " is not a finite value >= 0");
      const int j = skin.joints[v][k];
      if (j < 0 || static_cast<std::size_t>(j) >= skin.bones.size())
        throw std::invalid_argument(index_text("skin.joints", v) + ": bone " + std::to_string(j) +
                                    " outside [0, " + std::to_string(skin.bones.size()) + ")");
      total += w;
    }
    if (!(total > 0))
      throw std::invalid_argument(index_text("skin.weights", v) + ": the weights sum to 0");
  }
  for (std::size_t t = 0; t < skin.triangles.size(); ++t) {
    for (int idx : skin.triangles[t]) {
      if (idx < 0 || static_cast<std::size_t>(idx) >= n)
        throw std::invalid_argument(index_text("skin.triangles", t) + ": vertex " +
                                    std::to_string(idx) + " outside [0, " + std::to_string(n) +
                                    ")");
    }
  }
  for (std::size_t j = 0; j < skin.bones.size(); ++j) {
    if (skin.bones[j] < 1 || skin.bones[j] >= model.njoints)
      throw std::invalid_argument(index_text("skin.bones", j) + ": link " +
                                  std::to_string(skin.bones[j]) + " outside [1, " +
                                  std::to_string(model.njoints) + ")");
    const core::Transform& X = skin.inverse_bind[j];
    if (!X.R.allFinite() || !X.p.allFinite())
      throw std::invalid_argument(index_text("skin.inverse_bind", j) + ": not finite");
  }
  if (!skin.base_color.allFinite()) throw std::invalid_argument("skin.base_color: not finite");
}

ThumbnailScene build_thumbnail_scene(const core::Model& model,
                                     const Eigen::VectorXd& q,
                                     const ThumbnailOptions& options,
                                     const core::SkinnedMesh* skin) {
  if (model.njoints < 2) throw std::invalid_argument("model: no links to draw");
  const bool skinned = skin != nullptr && !skin->empty();

  core::Data posed(model), neutral(model);
  core::forward_kinematics(model, posed, q);
  core::forward_kinematics(model, neutral, core::neutral_configuration(model));

  // bounds of the pose, with the skin's vertices
  core::Bounds bounds = core::world_bounds(model, posed);
  std::vector<core::Transform> X_skin;
  std::vector<Vector3> skin_W;
  if (skinned) {
    skin_W = core::skinned_positions(*skin, posed.X_W, X_skin);
    for (const Vector3& p : skin_W) bounds.add(p);
  }
  const core::Bounds neutral_bounds = core::world_bounds(model, neutral);
  const double neutral_extent = std::max(neutral_bounds.size().maxCoeff(), 1e-3);
  // a figure of no extent still gets a frame of a few centimetres
  const Vector3 centre_W = 0.5 * (bounds.min + bounds.max);
  const Vector3 half = (0.5 * bounds.size()).cwiseMax(0.02 * neutral_extent);
  const double extent = 2 * half.maxCoeff();

  ThumbnailScene scene;
  scene.size = options.size;
  for (int k = 0; k < 3; ++k) scene.background[k] = options.background[k] / 255.0f;

  // the figure
  const SideTint tint{0.5 * (neutral_bounds.min.x() + neutral_bounds.max.x()),
                      0.02 * neutral_extent};
  if (skinned) {
    // a bone's side: where its link sits at the neutral configuration
    std::vector<Eigen::Vector3f> bone_tint;
    for (int bone : skin->bones) bone_tint.push_back(tint.colour(neutral.X_W[bone].p));
    append_skin(*skin, skin_W, X_skin, centre_W, bone_tint, scene.figure);
  } else {
    append_shapes(model, posed, neutral, centre_W, tint, 0.012 * neutral_extent, scene.figure);
  }

  // the camera: a 3/4 front view of the bounds' corners
  const double deg = std::numbers::pi / 180;
  const double azimuth = kCameraAzimuthDegrees * deg, elevation = kCameraElevationDegrees * deg;
  const Vector3 back(std::sin(azimuth) * std::cos(elevation), std::sin(elevation),
                     std::cos(azimuth) * std::cos(elevation));  // target → camera
  const Vector3 forward = -back;
  const Vector3 right = forward.cross(Vector3::UnitY()).normalized();
  const Vector3 up = right.cross(forward);
  CornerSet corners;
  corners.min_z = 1e300;
  corners.max_z = -1e300;
  for (int k = 0; k < 8; ++k) {
    const Vector3 c((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(),
                    (k & 4) ? half.z() : -half.z());
    corners.c.emplace_back(right.dot(c), up.dot(c), forward.dot(c));
    corners.min_z = std::min(corners.min_z, corners.c.back().z());
    corners.max_z = std::max(corners.max_z, corners.c.back().z());
  }
  const double t = std::tan(0.5 * kCameraFovDegrees * deg);
  const double reach = 10 * extent;
  double d = fitting_distance(corners, 1, 2 * kFillHeight, t, reach);
  const double d_width = fitting_distance(corners, 0, 2 * kMaxFillWidth, t, reach);
  d = std::max(d, d_width);
  const double a = centring_offset(corners, 0, d, t, reach);
  const double b = centring_offset(corners, 1, d, t, reach);
  const Vector3 eye_F = a * right + b * up - d * forward;

  // ground: y = 0, or the figure's lowest point when it reaches below 0
  const double ground_y_W = std::min(0.0, bounds.min.y());
  const double footprint = std::max(std::hypot(half.x(), half.z()), 0.1 * extent);
  scene.draw_shadow = options.ground != ThumbnailGround::kNone;
  scene.draw_grid = options.ground == ThumbnailGround::kGridAndShadow;
  scene.ground_y = static_cast<float>(ground_y_W - centre_W.y() - 1e-4 * extent);
  scene.shadow_radius = static_cast<float>(1.15 * footprint);
  scene.fade_radius = static_cast<float>(std::max(3.0 * footprint, 1.2 * extent));
  scene.grid_step = static_cast<float>(nice_step(extent / 6));

  // view and projection; far enough for the ground square around the figure
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = right.transpose();
  view.block<1, 3>(1, 0) = up.transpose();
  view.block<1, 3>(2, 0) = back.transpose();
  view.block<3, 1>(0, 3) = -view.block<3, 3>(0, 0) * eye_F;
  const double nearest = d + corners.min_z;
  const double near = std::max(0.5 * nearest, 1e-4 * extent);
  const double far = d + corners.max_z + 2.0 * scene.fade_radius + std::abs(scene.ground_y);
  scene.view_projection = perspective(kCameraFovDegrees * deg, near, far) * view.cast<float>();
  scene.eye_F = eye_F.cast<float>();
  return scene;
}

}  // namespace server
