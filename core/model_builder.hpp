// ModelBuilder: collects links and joints in any order, then finalize() validates them and
// produces an immutable Model with links in depth-first order.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model.hpp"

namespace core {

/// Thrown by ModelBuilder::finalize and by the file loaders. what() lists every violation, one
/// per line; each names the link or joint (and, from a loader, the file) and the rule it broke.
class ModelError : public std::runtime_error {
 public:
  explicit ModelError(std::vector<std::string> violations);
  const std::vector<std::string>& violations() const { return violations_; }

 private:
  std::vector<std::string> violations_;
};

/// The joint that connects a link to its parent.
struct JointSpec {
  std::string name;  // defaults to the link name when empty
  JointType type = JointType::kFixed;
  Transform X_PJ;  // joint frame in the parent link frame (the link frame is the joint frame)
  Vector3 axis = Vector3::UnitZ();  // revolute and prismatic; normalized by finalize()
  JointLimits limits;
  SphericalRange range;                                      // spherical only
  Quaternion standard_orientation = Quaternion::Identity();  // spherical only
  double ik_weight = 1.0;
  std::optional<double> ik_gain;
};

struct LinkSpec {
  std::string name;
  std::string parent;  // empty: attached to the world (the root)
  JointSpec joint;
  double mass = 0;
  Vector3 com = Vector3::Zero();    // centre of mass in the link frame
  Matrix3 I_com = Matrix3::Zero();  // rotational inertia about the COM, link-frame axes
  std::vector<Geometry> collision;
  std::vector<Geometry> visual;
  std::string display_name;
};

/// Limits that keep a hostile file from making the builder allocate without bound.
constexpr int kMaxLinks = 10000;
constexpr int kMaxRangeTriangles = 4096;

class ModelBuilder {
 public:
  explicit ModelBuilder(std::string model_name = "") : name_(std::move(model_name)) {}

  /// Adds a link with the joint to its parent; returns its insertion index.
  int add_link(LinkSpec link);
  void set_gravity(const Vector3& g) { gravity_ = g; }
  void set_source_dir(std::string dir) { source_dir_ = std::move(dir); }
  int size() const { return static_cast<int>(links_.size()); }
  const LinkSpec& link(int i) const { return links_[i]; }
  LinkSpec& link(int i) { return links_[i]; }

  /// Validates (one root, no cycles, unique names, finite numbers, physical inertias,
  /// lower <= upper, well-formed ranges and geometry) and builds the Model.
  /// @throws ModelError listing every violation
  std::shared_ptr<const Model> finalize() const;

 private:
  std::string name_;
  std::string source_dir_;
  Vector3 gravity_{0, -9.81, 0};
  std::vector<LinkSpec> links_;
};

}  // namespace core
