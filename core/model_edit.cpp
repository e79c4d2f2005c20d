#include "core/model_edit.hpp"

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

}  // namespace core
