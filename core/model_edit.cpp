#include "core/model_edit.hpp"

#include <algorithm>
#include <cmath>

#include "core/bounds.hpp"
#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace core {

ModelBuilder to_builder(const Model& model) {
  ModelBuilder b(model.name);
  b.set_gravity(model.gravity);
  b.set_source_dir(model.source_dir);
  for (int i = 1; i < model.njoints; ++i) {
    LinkSpec l;
    l.name = model.link_name[i];
    l.parent = model.parent[i] > 0 ? model.link_name[model.parent[i]] : std::string();
    l.display_name = model.display_name[i];
    JointSpec& j = l.joint;
    j.name = model.joint_name[i];
    j.type = model.joint_type[i];
    j.X_PJ = model.X_PJ[i];
    j.axis = model.axis[i];
    j.limits = model.limits[i];
    j.range = model.spherical_range[i];
    j.standard_orientation = model.standard_orientation[i];
    j.ik_weight = model.ik_weight[i];
    j.ik_gain = model.ik_gain[i];
    // spatial inertia back to mass, centre of mass and inertia about it
    const SpatialInertia& I = model.inertia[i];
    l.mass = I.mass;
    l.com = I.com();
    l.I_com = I.inertia_about_com();
    l.collision = model.collision[i];
    l.visual = model.visual[i];
    b.add_link(std::move(l));
  }
  return b;
}

std::shared_ptr<const Model> weld_root(const std::shared_ptr<const Model>& model) {
  if (model->njoints < 2 || model->joint_type[1] == JointType::kFixed) return model;
  ModelBuilder b = to_builder(*model);
  JointSpec& root = b.link(0).joint;
  root.type = JointType::kFixed;
  root.limits = JointLimits{};
  root.range = SphericalRange{};
  root.standard_orientation = Quaternion::Identity();
  return b.finalize();
}

namespace {

// `model` with its root joint's placement moved by the world-frame transform G (X_PJ ← G · X_PJ);
// its root joint becomes free when `float_root`
std::shared_ptr<const Model> move_root(const Model& model, const Transform& G, bool float_root) {
  ModelBuilder builder = to_builder(model);
  JointSpec& root = builder.link(0).joint;
  root.X_PJ = G * root.X_PJ;
  if (float_root) {
    root.type = JointType::kFree;
    root.limits = JointLimits{};
  }
  return builder.finalize();
}

// `model` with its root joint's placement raised by `lift` (m, down when negative)
std::shared_ptr<const Model> raise_root(const Model& model, double lift, bool float_root) {
  return move_root(model, Transform::from_translation(Vector3(0, lift, 0)), float_root);
}

}  // namespace

Grounded stand_on_ground(const std::shared_ptr<const Model>& model) {
  Grounded out{model, 0.0, false};
  if (model->njoints < 2) return out;
  Data data(*model);
  forward_kinematics(*model, data, rest_configuration(*model));
  const Bounds b = world_bounds(*model, data);
  if (b.empty() || !(b.size().y() > 0) || !std::isfinite(b.min.y())) return out;
  const double root_height = data.X_W[1].p.y();
  // a figure reaching far below its root stands on its limbs
  const bool legged = root_height - b.min.y() > 0.25 * b.size().y();
  const bool float_root = legged && model->joint_type[1] == JointType::kFixed;
  // already standing (to rounding: a placed figure placed again is itself)
  if (std::abs(b.min.y()) <= 1e-12 * b.size().y() && !float_root) return out;
  out.model = raise_root(*model, -b.min.y(), float_root);
  out.lift = -b.min.y();
  out.floated = float_root;
  return out;
}

namespace {

// The lowest height the figure reaches over the frames: skinned vertices when there is a mesh,
// else the links' shapes; +inf when there is nothing to measure.
double lowest_height_over(const Model& model,
                          const std::vector<Eigen::VectorXd>& frames,
                          const SkinnedMesh* skin) {
  const bool use_mesh = skin != nullptr && !skin->empty();
  const std::size_t n = frames.size();
  std::size_t stride = 1;
  if (use_mesh && n > 1) {
    const double frames_allowed = std::max(2.0, kGroundingVertexFrames / skin->positions.size());
    stride = static_cast<std::size_t>(std::ceil((n - 1) / (frames_allowed - 1)));
  }
  std::vector<std::size_t> measured;  // the frames measured: every stride-th, and the last
  for (std::size_t f = 0; f < n; f += stride) measured.push_back(f);
  if (n > 0 && measured.back() != n - 1) measured.push_back(n - 1);
  Data data(model);
  std::vector<Transform> X_skin;
  double lowest = kInfinity;
  for (std::size_t f : measured) {
    forward_kinematics(model, data, frames[f]);
    if (use_mesh) {
      for (const Vector3& p : skinned_positions(*skin, data.X_W, X_skin))
        lowest = std::min(lowest, p.y());
    } else {
      const Bounds b = world_bounds(model, data);
      if (!b.empty()) lowest = std::min(lowest, b.min.y());
    }
  }
  return lowest;
}

}  // namespace

Grounded stand_motion_on_ground(const std::shared_ptr<const Model>& model,
                                const std::vector<Eigen::VectorXd>& frames,
                                const SkinnedMesh* skin) {
  Grounded out{model, 0.0, false};
  if (model->njoints < 2) return out;
  const double lowest = frames.empty()
                            ? lowest_height_over(*model, {rest_configuration(*model)}, skin)
                            : lowest_height_over(*model, frames, skin);
  if (!std::isfinite(lowest)) return out;
  // already standing, to rounding relative to the figure's height
  const double height = neutral_height(*model);
  if (std::abs(lowest) <= 1e-12 * std::max(1.0, height)) return out;
  out.model = raise_root(*model, -lowest, false);
  out.lift = -lowest;
  return out;
}

std::shared_ptr<const Model> turn_root(const Model& model,
                                       const Matrix3& R,
                                       const Vector3& centre) {
  // G = T(c) · R · T(−c)
  Transform G;
  G.R = R;
  G.p = centre - R * centre;
  return move_root(model, G, false);
}

}  // namespace core
