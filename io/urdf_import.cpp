#include "io/urdf_import.hpp"

#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <utility>

#include "core/model_builder.hpp"
#include "io/urdf.hpp"
#include "io/urdf_mesh.hpp"

namespace io::urdf_internal {

using namespace core;  // io reads and writes core's types

namespace {

std::string six_digits(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

Matrix3 rotation(const urdf::Rotation& r) {
  return Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix();
}

Vector3 vec(const urdf::Vector3& v) { return Vector3(v.x, v.y, v.z); }

// ---------------------------------------------------------------------------------------------
// conversion
//
// Z-up → Y-up (DESIGN.md §2). Every link frame L keeps its origin; its coordinates are
// re-expressed with C = urdf_to_y_up():
//
//       [0 1 0]      v_ours = C v_urdf   (URDF x forward → our +Z, y left → our +X,
//   C = [0 0 1]                           z up → our +Y)
//       [1 0 0]
//
// so a joint placement X_PJ = (R, p) becomes (C R Cᵀ, C p), a joint axis a becomes C a, a centre
// of mass c becomes C c and an inertia I becomes C I Cᵀ. Products of re-expressed transforms are
// re-expressed products, hence every link's world pose becomes (C R_WL Cᵀ, C p_WL). A shape's own
// frame S is not re-expressed (mesh vertices and cylinder/capsule z axes stay as authored), so its
// pose in the link becomes X_L'S = (C, 0) · X_LS = (C R, C p).

class Converter {
 public:
  Converter(const Scan& scan, const MeshResolver& meshes)
      : scan_(scan), meshes_(meshes), C_(urdf_to_y_up()) {}

  Transform placement(const urdf::Pose& pose) const {
    return {C_ * rotation(pose.rotation) * C_.transpose(), C_ * vec(pose.position)};
  }

  // joint type, axis and limits of `j` into `spec` (placement and name are set by the caller)
  void joint(const urdf::Joint& j, JointSpec& spec) {
    const std::string who = "joint '" + j.name + "'";
    spec.name = j.name;
    spec.X_PJ = placement(j.parent_to_joint_origin_transform);
    spec.axis = C_ * vec(j.axis);
    switch (j.type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::PRISMATIC:
        spec.type = j.type == urdf::Joint::REVOLUTE ? JointType::kRevolute : JointType::kPrismatic;
        if (j.limits) {
          spec.limits = {j.limits->lower, j.limits->upper, j.limits->velocity, j.limits->effort};
          if (j.limits->lower == j.limits->upper) {
            warnings.push_back(who + ": lower = upper = " + six_digits(j.limits->lower) +
                               "; the joint cannot move inside its limits");
          }
        }
        break;
      case urdf::Joint::CONTINUOUS:
        spec.type = JointType::kRevolute;  // a revolute joint without a range
        if (j.limits) {
          spec.limits.velocity = j.limits->velocity;
          spec.limits.effort = j.limits->effort;
        }
        break;
      case urdf::Joint::FIXED:
        spec.type = JointType::kFixed;
        break;
      case urdf::Joint::FLOATING:
        spec.type = JointType::kFree;
        break;
      case urdf::Joint::PLANAR:
        errors.push_back(who +
                         ": type 'planar' is not supported (rule: joint types are revolute, "
                         "continuous, prismatic, fixed and floating)");
        break;
      default:
        errors.push_back(who +
                         ": unknown joint type (rule: joint types are revolute, "
                         "continuous, prismatic, fixed and floating)");
        break;
    }
  }

  // inertial and geometry of link `l` into `spec`
  void link(const urdf::Link& l, LinkSpec& spec) {
    spec.name = l.name;
    if (l.inertial) {
      const urdf::Inertial& in = *l.inertial;
      Matrix3 I;
      I << in.ixx, in.ixy, in.ixz,  //
          in.ixy, in.iyy, in.iyz,   //
          in.ixz, in.iyz, in.izz;
      // inertia given in the inertial frame: rotate into link axes (R I Rᵀ), then re-express
      const Matrix3 R = C_ * rotation(in.origin.rotation);
      const Matrix3 I_link = R * I * R.transpose();
      spec.mass = in.mass;
      spec.com = C_ * vec(in.origin.position);
      spec.I_com = 0.5 * (I_link + I_link.transpose());
    }
    const auto it = scan_.links.find(l.name);
    static const LinkScan kEmpty;
    const LinkScan& ls = it == scan_.links.end() ? kEmpty : it->second;
    shapes(l.name, "visual", l.visual_array, ls.visual, spec.visual);
    shapes(l.name, "collision", l.collision_array, ls.collision, spec.collision);
  }

  std::vector<std::string> warnings;
  std::vector<std::string> errors;

 private:
  template <class Element>
  void shapes(const std::string& link,
              const char* kind,
              const std::vector<std::shared_ptr<Element>>& elements,
              const std::vector<ShapeKind>& kinds,
              std::vector<Geometry>& out) {
    if (elements.size() != kinds.size()) {
      errors.push_back("link '" + link + "': urdfdom read " + std::to_string(elements.size()) +
                       " " + kind + " elements where the file has " + std::to_string(kinds.size()) +
                       " (rule: every <" + kind + "> must be readable)");
      return;
    }
    for (size_t k = 0; k < elements.size(); ++k) {
      if (!elements[k] || !elements[k]->geometry) continue;
      const urdf::Geometry& g = *elements[k]->geometry;
      Geometry shape;
      shape.X_LinkShape = {C_ * rotation(elements[k]->origin.rotation),
                           C_ * vec(elements[k]->origin.position)};
      switch (g.type) {
        case urdf::Geometry::SPHERE:
          shape.shape = Geometry::Shape::kSphere;
          shape.radius = static_cast<const urdf::Sphere&>(g).radius;
          break;
        case urdf::Geometry::BOX:
          shape.shape = Geometry::Shape::kBox;
          shape.size = vec(static_cast<const urdf::Box&>(g).dim);
          break;
        case urdf::Geometry::CYLINDER: {
          // a Bullet capsule arrives here renamed; Bullet builds btCapsuleShapeZ(radius, length),
          // whose height is the distance between the sphere centres, as our Geometry::length
          const auto& c = static_cast<const urdf::Cylinder&>(g);
          shape.shape = kinds[k] == ShapeKind::kCapsule ? Geometry::Shape::kCapsule
                                                        : Geometry::Shape::kCylinder;
          shape.radius = c.radius;
          shape.length = c.length;
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& m = static_cast<const urdf::Mesh&>(g);
          std::string why;
          const std::optional<std::string> path = meshes_.resolve(m.filename, why);
          if (!path) {
            warnings.push_back("link '" + link + "': " + kind + " mesh '" + m.filename + "' " +
                               why + "; shape dropped");
            continue;
          }
          shape.shape = Geometry::Shape::kMesh;
          shape.mesh = *path;
          shape.scale = vec(m.scale);
          break;
        }
      }
      out.push_back(std::move(shape));
    }
  }

  const Scan& scan_;
  const MeshResolver& meshes_;
  Matrix3 C_;
};

bool massless(const urdf::Link& l) { return !l.inertial || l.inertial->mass == 0.0; }

// How the model attaches to the world: a massless root named "world" is the world itself, and
// its one child joint is the root joint; otherwise the file does not say.
struct RootAttachment {
  urdf::LinkConstSharedPtr world;   // the dropped "world" link, or null
  urdf::JointConstSharedPtr joint;  // the URDF joint between the world and our root, or null
  std::string link;                 // our root link
};

RootAttachment find_root(const urdf::ModelInterface& model,
                         const std::string& src,
                         std::vector<std::string>& warnings) {
  const urdf::LinkConstSharedPtr root = model.getRoot();
  if (!root) fail(src, {"urdfdom found no root link (rule: exactly one link has no parent)"});
  if (root->name != "world" || !massless(*root)) return {nullptr, nullptr, root->name};
  if (root->child_joints.size() != 1) {
    fail(src, {"link 'world' is a massless root with " + std::to_string(root->child_joints.size()) +
               " child joints (rule: the world link connects to exactly one link, the model's "
               "root)"});
  }
  if (!root->visual_array.empty() || !root->collision_array.empty()) {
    warnings.push_back("link 'world' is the world frame, not a link; its geometry is ignored");
  }
  const urdf::JointConstSharedPtr joint = root->child_joints[0];
  return {root, joint, joint->child_link_name};
}

// every mesh URI in document order (they decide the model folder)
std::vector<std::string> mesh_uris(const urdf::ModelInterface& model, const Scan& scan) {
  std::vector<std::string> uris;
  auto add = [&](const auto& elements) {
    for (const auto& e : elements) {
      if (e && e->geometry && e->geometry->type == urdf::Geometry::MESH) {
        uris.push_back(static_cast<const urdf::Mesh&>(*e->geometry).filename);
      }
    }
  };
  for (const std::string& name : scan.link_order) {
    const urdf::LinkConstSharedPtr l = model.getLink(name);
    if (!l) continue;
    add(l->visual_array);
    add(l->collision_array);
  }
  return uris;
}

// links and their parent joints, in document order
void add_links(const urdf::ModelInterface& model,
               const Scan& scan,
               const RootAttachment& root,
               Converter& convert,
               ModelBuilder& builder) {
  for (const std::string& name : scan.link_order) {
    if (root.world && name == root.world->name) continue;
    const urdf::LinkConstSharedPtr l = model.getLink(name);
    if (!l) continue;
    LinkSpec spec;
    convert.link(*l, spec);
    if (name == root.link) {
      if (root.joint) convert.joint(*root.joint, spec.joint);
      spec.parent.clear();
    } else if (l->parent_joint) {
      convert.joint(*l->parent_joint, spec.joint);
      spec.parent = l->parent_joint->parent_link_name;
    }
    builder.add_link(std::move(spec));
  }
}

// the root joint: as in the file, or forced by the options
void set_root_joint(const urdf::ModelInterface& model,
                    const RootAttachment& root,
                    const LoadOptions& options,
                    ModelBuilder& builder,
                    std::vector<std::string>& warnings) {
  for (int i = 0; i < builder.size(); ++i) {
    LinkSpec& spec = builder.link(i);
    if (spec.name != root.link) continue;
    JointSpec& j = spec.joint;
    if (!root.joint) {
      // the file cannot say how its root attaches; the joint takes the link's name if unused
      std::string name = spec.name;
      while (model.getJoint(name)) name += "_root";
      j.name = name;
      j.type = options.root == RootJoint::kFree ? JointType::kFree : JointType::kFixed;
    } else if (options.root != RootJoint::kAsInFile) {
      const JointType want =
          options.root == RootJoint::kFree ? JointType::kFree : JointType::kFixed;
      if (j.type != want) {
        warnings.push_back("joint '" + j.name + "' (" + to_string(j.type) +
                           ") between 'world' and '" + spec.name + "' is replaced by a " +
                           to_string(want) + " joint, as the load options ask");
        j.type = want;
        j.limits = JointLimits{};
      }
    }
  }
}

}  // namespace

[[noreturn]] void fail(const std::string& source, const std::vector<std::string>& lines) {
  std::vector<std::string> out;
  out.reserve(lines.size());
  for (const std::string& l : lines) out.push_back(source + ": " + l);
  throw ModelError(std::move(out));
}

LoadResult import_urdf(const urdf::ModelInterface& model,
                       const Scan& scan,
                       const std::string& source,
                       const std::string& base_dir,
                       const LoadOptions& options,
                       std::vector<std::string> warnings) {
  const RootAttachment root = find_root(model, source, warnings);
  const MeshResolver meshes(base_dir, mesh_uris(model, scan));
  Converter convert(scan, meshes);
  std::string model_name = model.getName();
  if (model_name.empty()) model_name = std::filesystem::path(source).stem().string();
  ModelBuilder builder(model_name);
  builder.set_source_dir(meshes.root().string());
  add_links(model, scan, root, convert, builder);
  if (!convert.errors.empty()) fail(source, convert.errors);
  set_root_joint(model, root, options, builder, warnings);
  for (std::string& w : convert.warnings) warnings.push_back(std::move(w));

  LoadResult result;
  try {
    result.model = builder.finalize();
  } catch (const ModelError& e) {
    fail(source, e.violations());
  }
  if (warnings.size() > kMaxUrdfWarnings) {
    const size_t more = warnings.size() - (kMaxUrdfWarnings - 1);
    warnings.resize(kMaxUrdfWarnings - 1);
    warnings.push_back(std::to_string(more) + " more warnings are not listed");
  }
  for (const std::string& w : warnings) result.warnings.push_back(source + ": " + w);
  return result;
}

}  // namespace io::urdf_internal
