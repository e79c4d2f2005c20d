#include "core/model.hpp"

#include <numeric>

namespace core {

const char* to_string(JointType t) {
  switch (t) {
    case JointType::kFixed:
      return "fixed";
    case JointType::kRevolute:
      return "revolute";
    case JointType::kPrismatic:
      return "prismatic";
    case JointType::kSpherical:
      return "spherical";
    case JointType::kFree:
      return "free";
  }
  return "?";
}

std::optional<JointType> joint_type_from_string(std::string_view s) {
  for (JointType t : {JointType::kFixed, JointType::kRevolute, JointType::kPrismatic,
                      JointType::kSpherical, JointType::kFree}) {
    if (s == to_string(t)) return t;
  }
  return std::nullopt;
}

const char* to_string(Geometry::Shape s) {
  switch (s) {
    case Geometry::Shape::kCapsule:
      return "capsule";
    case Geometry::Shape::kSphere:
      return "sphere";
    case Geometry::Shape::kBox:
      return "box";
    case Geometry::Shape::kCylinder:
      return "cylinder";
    case Geometry::Shape::kMesh:
      return "mesh";
  }
  return "?";
}

std::optional<Geometry::Shape> shape_from_string(std::string_view s) {
  using S = Geometry::Shape;
  for (S shape : {S::kCapsule, S::kSphere, S::kBox, S::kCylinder, S::kMesh}) {
    if (s == to_string(shape)) return shape;
  }
  return std::nullopt;
}

bool SphericalRange::operator==(const SphericalRange& o) const {
  return frame.coeffs() == o.frame.coeffs() && swing == o.swing && triangles == o.triangles &&
         twist_lower == o.twist_lower && twist_upper == o.twist_upper;
}

int Model::link_index(std::string_view link) const {
  for (int i = 1; i < njoints; ++i) {
    if (link_name[i] == link) return i;
  }
  return -1;
}

int Model::path_last_v(int link) const {
  for (int j = link; j > 0; j = parent[j]) {
    const int n = joint_nv(joint_type[j]);
    if (n > 0) return idx_v[j] + n - 1;
  }
  return -1;
}

int Model::joint_index(std::string_view joint) const {
  for (int i = 1; i < njoints; ++i) {
    if (joint_name[i] == joint) return i;
  }
  return -1;
}

double Model::total_mass() const {
  double m = 0;
  for (int i = 1; i < njoints; ++i) m += inertia[i].mass;
  return m;
}

bool Model::operator==(const Model& o) const {
  if (standard_orientation.size() != o.standard_orientation.size()) return false;
  for (size_t i = 0; i < standard_orientation.size(); ++i) {
    if (standard_orientation[i].coeffs() != o.standard_orientation[i].coeffs()) return false;
  }
  return name == o.name && njoints == o.njoints && nq == o.nq && nv == o.nv &&
         gravity == o.gravity && parent == o.parent && subtree_end == o.subtree_end &&
         link_name == o.link_name && joint_name == o.joint_name && display_name == o.display_name &&
         joint_type == o.joint_type && X_PJ == o.X_PJ && axis == o.axis &&
         axis_index == o.axis_index && placement_is_translation == o.placement_is_translation &&
         idx_q == o.idx_q && idx_v == o.idx_v && limits == o.limits &&
         spherical_range == o.spherical_range && range_inner == o.range_inner &&
         ik_weight == o.ik_weight && ik_gain == o.ik_gain && inertia == o.inertia &&
         collision == o.collision && visual == o.visual && joint_of_v == o.joint_of_v &&
         parent_v == o.parent_v && chain_start_v == o.chain_start_v;
}

}  // namespace core
