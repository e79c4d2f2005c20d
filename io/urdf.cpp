#include "io/urdf.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "core/model_builder.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace fs = std::filesystem;

Matrix3 urdf_to_y_up() {
  // rows: our x = URDF y (left), our y = URDF z (up), our z = URDF x (forward); det C = +1
  Matrix3 C;
  C << 0, 1, 0,  //
      0, 0, 1,   //
      1, 0, 0;
  return C;
}

namespace {

// ---------------------------------------------------------------------------------------------
// urdfdom messages
//
// urdfdom reports through console_bridge, whose output handler is process-wide. Parses are
// therefore serialized by one mutex, and the handler object lives for the whole process because
// console_bridge keeps a pointer to it (as the "previous" handler) after we restore the caller's.
// This is the one piece of static mutable state in the loader; console_bridge's API forces it.

struct UrdfdomMessage {
  console_bridge::LogLevel level;
  std::string text;
};

class UrdfdomLog final : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    // console_bridge calls handlers under its own lock, so the sink is never written concurrently
    if (std::vector<UrdfdomMessage>* sink = sink_.load()) {
      sink->push_back({level, text});
    } else if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      std::fprintf(stderr, "urdfdom: %s\n", text.c_str());  // reinstated by someone else
    }
  }
  std::atomic<std::vector<UrdfdomMessage>*> sink_{nullptr};
};

std::mutex& urdfdom_mutex() {
  static std::mutex m;
  return m;
}

UrdfdomLog& urdfdom_log() {
  static UrdfdomLog* const log = new UrdfdomLog;  // never destroyed, see above
  return *log;
}

// runs urdf::parseURDF with console_bridge output captured into `messages`
urdf::ModelInterfaceSharedPtr parse_with_urdfdom(const std::string& xml,
                                                 std::vector<UrdfdomMessage>& messages) {
  const std::lock_guard<std::mutex> lock(urdfdom_mutex());
  UrdfdomLog& log = urdfdom_log();
  const console_bridge::LogLevel saved_level = console_bridge::getLogLevel();
  log.sink_.store(&messages);
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  console_bridge::useOutputHandler(&log);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    messages.push_back({console_bridge::CONSOLE_BRIDGE_LOG_ERROR, e.what()});
    model.reset();
  }
  console_bridge::restorePreviousOutputHandler();
  console_bridge::setLogLevel(saved_level);
  log.sink_.store(nullptr);
  return model;
}

// ---------------------------------------------------------------------------------------------
// small helpers

std::string num(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

std::string attr(const tinyxml2::XMLElement* e, const char* name) {
  const char* v = e->Attribute(name);
  return v ? std::string(v) : std::string();
}

std::string line_of(const tinyxml2::XMLElement* e) {
  return "line " + std::to_string(e->GetLineNum());
}

Matrix3 rotation(const urdf::Rotation& r) {
  return Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix();
}

Vector3 vec(const urdf::Vector3& v) { return Vector3(v.x, v.y, v.z); }

// ---------------------------------------------------------------------------------------------
// tinyxml2 scan: what urdfdom drops or cannot read

enum class ShapeKind { kStandard, kCapsule };

struct LinkScan {
  std::vector<ShapeKind> visual;     // one per <visual> left for urdfdom, in document order
  std::vector<ShapeKind> collision;  // one per <collision> left for urdfdom
};

struct JointScan {
  std::string name, parent, child;  // parent and child link names
  int line = 0;
};

struct Scan {
  std::vector<std::string> link_order;  // link names in document order
  std::unordered_map<std::string, LinkScan> links;
  std::vector<JointScan> joints;      // in document order
  std::vector<std::string> warnings;  // without the source prefix
  std::vector<std::string> errors;
};

struct TagCount {
  int count = 0;
  int first_line = 0;
};

void count_tag(std::map<std::string, TagCount>& tags, const tinyxml2::XMLElement* e) {
  TagCount& t = tags[e->Name()];
  if (t.count++ == 0) t.first_line = e->GetLineNum();
}

// <visual> or <collision>: renames Bullet's <capsule> to <cylinder> for urdfdom (same radius and
// length attributes) and remembers it; returns false when the element must be removed
bool scan_shape(tinyxml2::XMLElement* shape,
                const std::string& link,
                const char* kind,
                std::vector<ShapeKind>& out,
                int& materials,
                Scan& scan) {
  const std::string where = "link '" + link + "': " + kind + " (" + line_of(shape) + ")";
  int geometries = 0;
  for (tinyxml2::XMLElement* c = shape->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "geometry") {
      if (++geometries > 1) {
        scan.warnings.push_back(where + ": only the first <geometry> is used; the <geometry> at " +
                                line_of(c) + " is ignored");
      }
    } else if (tag == "material" && std::string(kind) == "visual") {
      ++materials;
    } else if (tag != "origin") {
      scan.warnings.push_back(where + ": <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
  tinyxml2::XMLElement* geometry = shape->FirstChildElement("geometry");
  tinyxml2::XMLElement* g = geometry ? geometry->FirstChildElement() : nullptr;
  if (!g) {
    out.push_back(ShapeKind::kStandard);  // urdfdom reports the missing geometry
    return true;
  }
  for (const tinyxml2::XMLElement* extra = g->NextSiblingElement(); extra;
       extra = extra->NextSiblingElement()) {
    scan.warnings.push_back(where + ": only the first shape in <geometry> is used; <" +
                            std::string(extra->Name()) + "> (" + line_of(extra) + ") is ignored");
  }
  const std::string type = g->Name();
  if (type == "box" || type == "sphere" || type == "cylinder" || type == "mesh") {
    out.push_back(ShapeKind::kStandard);
    return true;
  }
  if (type == "capsule") {
    if (!g->Attribute("radius") || !g->Attribute("length")) {
      scan.errors.push_back(where +
                            ": <capsule> needs radius and length attributes (rule: "
                            "Bullet's capsule is <capsule radius=\"r\" length=\"l\"/>)");
      return false;
    }
    scan.warnings.push_back(where + ": <capsule radius=\"" + attr(g, "radius") + "\" length=\"" +
                            attr(g, "length") +
                            "\"> is a non-standard Bullet extension; read as a capsule along its "
                            "z axis, length between the sphere centres");
    g->SetName("cylinder");  // urdfdom then reads radius, length and the origin for us
    out.push_back(ShapeKind::kCapsule);
    return true;
  }
  scan.warnings.push_back(where + ": geometry <" + type +
                          "> is not supported (supported: box, sphere, cylinder, mesh, capsule); "
                          "shape dropped");
  return false;
}

void scan_link(tinyxml2::XMLElement* link, int& materials, Scan& scan) {
  const char* name_attr = link->Attribute("name");
  if (!name_attr) return;  // urdfdom reports the missing name
  const std::string name = name_attr;
  const bool first = scan.links.find(name) == scan.links.end();
  LinkScan& ls = scan.links[name];
  if (first) scan.link_order.push_back(name);
  int inertials = 0;
  std::vector<tinyxml2::XMLElement*> removed;
  for (tinyxml2::XMLElement* c = link->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "inertial") {
      if (++inertials > 1) {
        scan.warnings.push_back("link '" + name +
                                "': only the first <inertial> is used; the "
                                "<inertial> at " +
                                line_of(c) + " is ignored");
      }
      for (const tinyxml2::XMLElement* i = c->FirstChildElement(); i; i = i->NextSiblingElement()) {
        const std::string t = i->Name();
        if (t != "origin" && t != "mass" && t != "inertia") {
          scan.warnings.push_back("link '" + name + "': <inertial> child <" + t + "> (" +
                                  line_of(i) + ") is not supported and is ignored");
        }
      }
    } else if (tag == "visual") {
      if (!scan_shape(c, name, "visual", ls.visual, materials, scan)) removed.push_back(c);
    } else if (tag == "collision") {
      if (!scan_shape(c, name, "collision", ls.collision, materials, scan)) removed.push_back(c);
    } else {
      scan.warnings.push_back("link '" + name + "': <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
  for (tinyxml2::XMLElement* e : removed) link->DeleteChild(e);
}

void scan_joint(const tinyxml2::XMLElement* joint, Scan& scan) {
  const std::string name = attr(joint, "name");
  const std::string who = "joint '" + name + "'";
  const tinyxml2::XMLElement* parent = joint->FirstChildElement("parent");
  const tinyxml2::XMLElement* child = joint->FirstChildElement("child");
  scan.joints.push_back({name, parent ? attr(parent, "link") : "", child ? attr(child, "link") : "",
                         joint->GetLineNum()});
  for (const tinyxml2::XMLElement* c = joint->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "origin" || tag == "parent" || tag == "child" || tag == "axis" || tag == "limit") {
      continue;
    }
    if (tag == "mimic") {
      std::string how;
      if (c->Attribute("multiplier")) how += "multiplier " + attr(c, "multiplier");
      if (c->Attribute("offset"))
        how += std::string(how.empty() ? "" : ", ") + "offset " + attr(c, "offset");
      scan.warnings.push_back(who + ": mimic of '" + attr(c, "joint") + "'" +
                              (how.empty() ? "" : " (" + how + ")") +
                              " is not supported; the joint moves independently");
    } else if (tag == "dynamics" || tag == "safety_controller" || tag == "calibration") {
      std::string attrs;
      for (const tinyxml2::XMLAttribute* a = c->FirstAttribute(); a; a = a->Next()) {
        attrs += std::string(" ") + a->Name();
      }
      scan.warnings.push_back(who + ": <" + tag + attrs + "> is ignored");
    } else {
      scan.warnings.push_back(who + ": <" + tag + "> (" + line_of(c) +
                              ") is not supported and is ignored");
    }
  }
}

// The links must form a tree. Checked before urdfdom runs: urdfdom keeps only the last of several
// parent joints of a link, and on a cycle without a root it fails after building a reference
// cycle of shared_ptrs that is never freed.
void check_topology(Scan& scan) {
  std::unordered_map<std::string, std::vector<const JointScan*>> parents_of;  // child → joints
  std::vector<std::string> children;  // in document order of their first parent joint
  for (const JointScan& j : scan.joints) {
    if (j.parent.empty() || j.child.empty()) continue;  // urdfdom reports the missing link
    auto& list = parents_of[j.child];
    if (list.empty()) children.push_back(j.child);
    list.push_back(&j);
  }
  for (const std::string& child : children) {
    const auto& list = parents_of[child];
    if (list.size() < 2) continue;
    std::string names;
    for (const JointScan* j : list) {
      names += (names.empty() ? "'" : ", '") + j->name + "' (line " + std::to_string(j->line) + ")";
    }
    scan.errors.push_back("link '" + child + "' is the child of " + std::to_string(list.size()) +
                          " joints " + names +
                          " (rule: a link has at most one parent joint; the links form a tree)");
  }
  if (!scan.errors.empty()) return;
  // walk up from every link; meeting the current path again closes a cycle
  enum Mark { kUnseen, kOnPath, kDone };
  std::unordered_map<std::string, Mark> mark;
  for (const std::string& start : children) {
    std::vector<std::string> path;
    std::string link = start;
    while (mark[link] == kUnseen && parents_of.count(link)) {
      mark[link] = kOnPath;
      path.push_back(link);
      link = parents_of[link].front()->parent;
    }
    if (mark[link] == kOnPath) {
      const auto first = std::find(path.begin(), path.end(), link);
      std::string links, joints;
      for (auto it = first; it != path.end(); ++it) {
        links += (links.empty() ? "'" : ", '") + *it + "'";
        joints += (joints.empty() ? "'" : ", '") + parents_of[*it].front()->name + "'";
      }
      scan.errors.push_back("links " + links + " form a cycle through joints " + joints +
                            " (rule: the links form a tree, no cycles)");
    }
    for (const std::string& l : path) mark[l] = kDone;
  }
}

Scan scan_document(tinyxml2::XMLElement* robot) {
  Scan scan;
  std::map<std::string, TagCount> ignored;  // top-level elements we do not read
  int materials = 0;
  int links = 0;
  for (tinyxml2::XMLElement* c = robot->FirstChildElement(); c; c = c->NextSiblingElement()) {
    const std::string tag = c->Name();
    if (tag == "link") {
      if (++links > kMaxLinks) {
        // count the rest without scanning them, so the message gives the real size
        for (tinyxml2::XMLElement* r = c->NextSiblingElement("link"); r;
             r = r->NextSiblingElement("link")) {
          ++links;
        }
        scan.errors.push_back("model has " + std::to_string(links) + " links (rule: at most " +
                              std::to_string(kMaxLinks) + " links)");
        return scan;
      }
      scan_link(c, materials, scan);
    } else if (tag == "joint") {
      scan_joint(c, scan);
    } else if (tag == "material") {
      ++materials;
    } else {
      count_tag(ignored, c);
    }
  }
  check_topology(scan);
  if (materials > 0) {
    scan.warnings.push_back(std::to_string(materials) +
                            " <material> elements are ignored (colours and textures are not "
                            "imported)");
  }
  for (const auto& [tag, t] : ignored) {
    scan.warnings.push_back("<" + tag + "> elements are ignored (" + std::to_string(t.count) +
                            " found, the first at line " + std::to_string(t.first_line) + ")");
  }
  return scan;
}

// ---------------------------------------------------------------------------------------------
// mesh paths

// true when p (absolute, lexically normal) lies strictly inside root (absolute, normal)
bool inside(const fs::path& p, const fs::path& root) {
  const fs::path rel = p.lexically_relative(root);
  if (rel.empty() || rel == ".") return false;
  return *rel.begin() != "..";
}

// nearest folder named `package` among `dir` and its ancestors, or empty
fs::path find_package(const fs::path& dir, const std::string& package) {
  if (dir.empty() || package.empty() || package == "." || package == ".." ||
      package.find('/') != std::string::npos) {
    return {};
  }
  for (fs::path p = dir;; p = p.parent_path()) {
    if (p.filename() == package) return p;
    if (p == p.parent_path()) return {};
  }
}

std::optional<std::pair<std::string, std::string>> split_package_uri(const std::string& uri) {
  constexpr std::string_view kPrefix = "package://";
  if (uri.rfind(kPrefix, 0) != 0) return std::nullopt;
  const std::string rest = uri.substr(kPrefix.size());
  const size_t slash = rest.find('/');
  if (slash == std::string::npos) return std::pair<std::string, std::string>{rest, ""};
  return std::pair<std::string, std::string>{rest.substr(0, slash), rest.substr(slash + 1)};
}

class MeshResolver {
 public:
  // urdf_dir: the URDF's folder (may be empty); uris: every mesh URI in document order
  MeshResolver(const std::string& base_dir, const std::vector<std::string>& uris) {
    if (base_dir.empty()) return;
    std::error_code ec;
    urdf_dir_ = fs::weakly_canonical(fs::absolute(base_dir, ec), ec).lexically_normal();
    if (ec) urdf_dir_ = fs::absolute(base_dir).lexically_normal();
    root_ = urdf_dir_;
    // the first package:// that resolves to an ancestor makes that package the model folder
    for (const std::string& uri : uris) {
      if (auto pkg = split_package_uri(uri)) {
        const fs::path dir = find_package(urdf_dir_, pkg->first);
        if (!dir.empty()) {
          root_ = dir;
          break;
        }
      }
    }
  }

  const fs::path& root() const { return root_; }

  // path of the mesh relative to root(), or nullopt with the reason in `why`
  std::optional<std::string> resolve(const std::string& uri, std::string& why) const {
    if (root_.empty()) {
      why = "cannot be resolved: no model folder was given (URDF text without a base folder)";
      return std::nullopt;
    }
    if (uri.empty()) {
      why = "has an empty filename";
      return std::nullopt;
    }
    fs::path candidate;
    if (auto pkg = split_package_uri(uri)) {
      const fs::path dir = find_package(urdf_dir_, pkg->first);
      if (dir.empty()) {
        why = "names package '" + pkg->first + "', but no folder of that name contains " +
              urdf_dir_.string() +
              " (rule: package://PKG resolves to the nearest ancestor "
              "folder named PKG)";
        return std::nullopt;
      }
      candidate = dir / pkg->second;
    } else if (uri.rfind("file://", 0) == 0) {
      const fs::path p = uri.substr(7);
      candidate = p.is_absolute() ? p : urdf_dir_ / p;
    } else if (uri.find("://") != std::string::npos) {
      why = "uses the URI scheme '" + uri.substr(0, uri.find("://")) +
            "', which is not supported (supported: package://, file://, plain paths)";
      return std::nullopt;
    } else {
      const fs::path p = uri;
      candidate = p.is_absolute() ? p : urdf_dir_ / p;
    }
    candidate = candidate.lexically_normal();
    const std::string rule =
        " (rule: meshes must lie inside the model folder " + root_.string() + "); refused";
    if (!inside(candidate, root_)) {
      why = "resolves to " + candidate.string() + ", outside the model folder" + rule;
      return std::nullopt;
    }
    std::error_code ec;
    if (!fs::exists(candidate, ec)) {
      why = "was not found (looked for " + candidate.string() + ")";
      return std::nullopt;
    }
    const fs::path real = fs::canonical(candidate, ec);
    if (ec) {
      why = "cannot be resolved: " + ec.message();
      return std::nullopt;
    }
    if (!inside(real, root_)) {
      why = "resolves through a symbolic link to " + real.string() + ", outside the model folder" +
            rule;
      return std::nullopt;
    }
    if (!fs::is_regular_file(real, ec)) {
      why = "resolves to " + real.string() + ", which is not a regular file";
      return std::nullopt;
    }
    return real.lexically_relative(root_).generic_string();
  }

 private:
  fs::path urdf_dir_;
  fs::path root_;
};

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
            warnings.push_back(who + ": lower = upper = " + num(j.limits->lower) +
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

[[noreturn]] void fail(const std::string& source, const std::vector<std::string>& lines) {
  std::vector<std::string> out;
  out.reserve(lines.size());
  for (const std::string& l : lines) out.push_back(source + ": " + l);
  throw ModelError(std::move(out));
}

std::vector<std::string> urdfdom_lines(const std::vector<UrdfdomMessage>& messages) {
  std::vector<std::string> out;
  for (const UrdfdomMessage& m : messages) {
    if (m.level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) out.push_back("urdfdom: " + m.text);
  }
  return out;
}

bool massless(const urdf::Link& l) { return !l.inertial || l.inertial->mass == 0.0; }

// urdfdom links own their children through shared_ptr; a cyclic file makes a reference cycle
// that would never be freed, so the links' tree pointers are cleared when we are done
class UrdfdomModelGuard {
 public:
  explicit UrdfdomModelGuard(urdf::ModelInterfaceSharedPtr model) : model_(std::move(model)) {}
  ~UrdfdomModelGuard() {
    if (!model_) return;
    for (auto& [name, link] : model_->links_) {
      link->child_links.clear();
      link->child_joints.clear();
      link->parent_joint.reset();
    }
  }
  UrdfdomModelGuard(const UrdfdomModelGuard&) = delete;
  UrdfdomModelGuard& operator=(const UrdfdomModelGuard&) = delete;

 private:
  urdf::ModelInterfaceSharedPtr model_;
};

}  // namespace

LoadResult load_urdf_string(const std::string& xml,
                            const std::string& source_name,
                            const std::string& base_dir,
                            const LoadOptions& options) {
  const std::string& src = source_name;
  if (xml.size() > kMaxUrdfBytes) {
    fail(src, {"file is " + std::to_string(xml.size()) + " bytes (rule: a URDF is at most " +
               std::to_string(kMaxUrdfBytes) + " bytes)"});
  }

  // well-formed XML first (tinyxml2 gives a line); urdfdom's own message goes with it
  tinyxml2::XMLDocument doc(true, tinyxml2::PRESERVE_WHITESPACE);
  doc.Parse(xml.data(), xml.size());
  tinyxml2::XMLElement* robot = doc.Error() ? nullptr : doc.FirstChildElement("robot");
  if (!robot) {
    std::vector<std::string> lines;
    if (doc.Error()) {
      lines.push_back(std::string("not well-formed XML (rule: a URDF is an XML document): ") +
                      doc.ErrorStr());
    } else {
      lines.push_back("no <robot> element (rule: a URDF's root element is <robot>)");
    }
    // urdfdom's message too, when its XML parser (TinyXML) also rejects the text; where TinyXML
    // is more lenient urdfdom would build a model from text that is not XML, and on a rootless
    // cycle it fails after building a shared_ptr cycle it never frees
    TiXmlDocument tinyxml;
    tinyxml.Parse(xml.c_str());
    if (tinyxml.Error() || !doc.Error()) {
      std::vector<UrdfdomMessage> messages;
      const UrdfdomModelGuard release_cycles(parse_with_urdfdom(xml, messages));
      for (std::string& l : urdfdom_lines(messages)) lines.push_back(std::move(l));
    } else {
      lines.push_back(
          "urdfdom's XML parser (TinyXML) accepts the text, but it is not "
          "well-formed XML");
    }
    fail(src, lines);
  }

  // what urdfdom drops: warnings, capsules, unsupported shapes (removed from the document)
  Scan scan = scan_document(robot);
  if (!scan.errors.empty()) fail(src, scan.errors);

  // urdfdom reads the document as tinyxml2 prints it back, so both see the same names (the
  // topology checks above hold for what urdfdom builds); any error it reports is fatal, since
  // it otherwise drops the element and goes on
  tinyxml2::XMLPrinter printer;
  doc.Print(&printer);
  const std::string text(printer.CStr(), static_cast<size_t>(printer.CStrSize() - 1));
  std::vector<UrdfdomMessage> messages;
  const urdf::ModelInterfaceSharedPtr model = parse_with_urdfdom(text, messages);
  const UrdfdomModelGuard release_cycles(model);
  std::vector<std::string> urdfdom_errors = urdfdom_lines(messages);
  if (!model || !urdfdom_errors.empty()) {
    if (urdfdom_errors.empty()) urdfdom_errors.push_back("urdfdom rejected the file");
    urdfdom_errors.push_back(
        "urdfdom could not read the file completely (rule: the file must "
        "be valid URDF; nothing was loaded)");
    fail(src, urdfdom_errors);
  }

  LoadResult result;
  auto warn = [&](const std::string& w) { result.warnings.push_back(src + ": " + w); };
  std::unordered_set<std::string> seen;  // urdfdom repeats some warnings per shape list
  for (const UrdfdomMessage& m : messages) {
    if (m.level == console_bridge::CONSOLE_BRIDGE_LOG_WARN && seen.insert(m.text).second) {
      warn("urdfdom: " + m.text);
    }
  }
  for (const std::string& w : scan.warnings) warn(w);

  // root: a massless "world" link is the world itself; its one child joint is the root joint
  const urdf::LinkConstSharedPtr urdf_root = model->getRoot();
  if (!urdf_root) fail(src, {"urdfdom found no root link (rule: exactly one link has no parent)"});
  std::string dropped_world;
  urdf::JointConstSharedPtr root_joint;  // URDF joint connecting our root link to the world
  if (urdf_root->name == "world" && massless(*urdf_root)) {
    if (urdf_root->child_joints.size() != 1) {
      fail(src, {"link 'world' is a massless root with " +
                 std::to_string(urdf_root->child_joints.size()) +
                 " child joints (rule: the world link connects to exactly one link, the model's "
                 "root)"});
    }
    dropped_world = urdf_root->name;
    root_joint = urdf_root->child_joints[0];
    if (!urdf_root->visual_array.empty() || !urdf_root->collision_array.empty()) {
      warn("link 'world' is the world frame, not a link; its geometry is ignored");
    }
  }

  // meshes: every URI in document order decides the model folder
  std::vector<std::string> uris;
  for (const std::string& name : scan.link_order) {
    const urdf::LinkConstSharedPtr l = model->getLink(name);
    if (!l) continue;
    for (const auto& v : l->visual_array) {
      if (v && v->geometry && v->geometry->type == urdf::Geometry::MESH) {
        uris.push_back(static_cast<const urdf::Mesh&>(*v->geometry).filename);
      }
    }
    for (const auto& c : l->collision_array) {
      if (c && c->geometry && c->geometry->type == urdf::Geometry::MESH) {
        uris.push_back(static_cast<const urdf::Mesh&>(*c->geometry).filename);
      }
    }
  }
  const MeshResolver meshes(base_dir, uris);

  // links and joints, in document order
  Converter convert(scan, meshes);
  std::string model_name = model->getName();
  if (model_name.empty()) model_name = fs::path(src).stem().string();
  ModelBuilder builder(model_name);
  builder.set_source_dir(meshes.root().string());
  const std::string root_name = root_joint ? root_joint->child_link_name : urdf_root->name;
  for (const std::string& name : scan.link_order) {
    if (name == dropped_world) continue;
    const urdf::LinkConstSharedPtr l = model->getLink(name);
    if (!l) continue;
    LinkSpec spec;
    convert.link(*l, spec);
    if (name == root_name) {
      if (root_joint) convert.joint(*root_joint, spec.joint);
      spec.parent.clear();
    } else if (l->parent_joint) {
      convert.joint(*l->parent_joint, spec.joint);
      spec.parent = l->parent_joint->parent_link_name;
    }
    builder.add_link(std::move(spec));
  }
  if (!convert.errors.empty()) fail(src, convert.errors);

  // root joint: as in the file, or forced by the options
  for (int i = 0; i < builder.size(); ++i) {
    LinkSpec& spec = builder.link(i);
    if (spec.name != root_name) continue;
    JointSpec& j = spec.joint;
    if (!root_joint) {
      // the file cannot say how its root attaches; the joint takes the link's name if unused
      std::string name = spec.name;
      while (model->getJoint(name)) name += "_root";
      j.name = name;
      j.type = options.root == RootJoint::kFree ? JointType::kFree : JointType::kFixed;
    } else if (options.root != RootJoint::kAsInFile) {
      const JointType want =
          options.root == RootJoint::kFree ? JointType::kFree : JointType::kFixed;
      if (j.type != want) {
        warn("joint '" + j.name + "' (" + to_string(j.type) + ") between 'world' and '" +
             spec.name + "' is replaced by a " + to_string(want) +
             " joint, as the load options ask");
        j.type = want;
        j.limits = JointLimits{};
      }
    }
  }
  for (const std::string& w : convert.warnings) warn(w);

  try {
    result.model = builder.finalize();
  } catch (const ModelError& e) {
    fail(src, e.violations());
  }
  if (result.warnings.size() > kMaxUrdfWarnings) {
    const size_t more = result.warnings.size() - (kMaxUrdfWarnings - 1);
    result.warnings.resize(kMaxUrdfWarnings - 1);
    warn(std::to_string(more) + " more warnings are not listed");
  }
  return result;
}

LoadResult load_urdf_file(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  const fs::path p(path);
  if (!fs::is_regular_file(p, ec)) {
    fail(path, {fs::exists(p, ec) ? "is not a regular file" : "file not found"});
  }
  const std::uintmax_t size = fs::file_size(p, ec);
  if (ec) fail(path, {"cannot read the file size: " + ec.message()});
  if (size > kMaxUrdfBytes) {
    fail(path, {"file is " + std::to_string(size) + " bytes (rule: a URDF is at most " +
                std::to_string(kMaxUrdfBytes) + " bytes)"});
  }
  std::ifstream in(p, std::ios::binary);
  if (!in) fail(path, {"cannot open the file for reading"});
  std::string xml(static_cast<size_t>(size), '\0');
  in.read(xml.data(), static_cast<std::streamsize>(size));
  xml.resize(static_cast<size_t>(in.gcount()));
  return load_urdf_string(xml, path, fs::absolute(p, ec).parent_path().string(), options);
}

}  // namespace io
