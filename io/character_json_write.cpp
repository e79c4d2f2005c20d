// Model to character JSON: a small ordered tree, printed with short arrays and small flat objects
// on one line, numbers in shortest round-trip form (io::json_number), rotations as 3×3 matrices
// and inertias in the form that reads back bit for bit (character_json_inertia.cpp).
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <utility>

#include "io/atomic_file.hpp"
#include "io/character_json_internal.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using Json = nlohmann::json;
using character_json::inertia_form;
using character_json::InertiaForm;
using character_json::one_dof;

struct Node {
  enum class Kind { kScalar, kArray, kObject } kind = Kind::kScalar;
  std::string text;               // kScalar: serialized JSON
  std::vector<Node> items;        // kArray: the elements; kObject: the values
  std::vector<std::string> keys;  // kObject: the keys, in order

  static Node scalar(std::string t) {
    Node n;
    n.text = std::move(t);
    return n;
  }
  static Node array() {
    Node n;
    n.kind = Kind::kArray;
    return n;
  }
  static Node object() {
    Node n;
    n.kind = Kind::kObject;
    return n;
  }
  Node& add(std::string key, Node value) {
    keys.push_back(std::move(key));
    items.push_back(std::move(value));
    return items.back();
  }
  Node& push(Node value) {
    items.push_back(std::move(value));
    return items.back();
  }
  bool empty() const { return items.empty(); }
  // printed on one line: scalars, arrays of scalars, objects of at most six scalars
  bool flat() const {
    if (kind == Kind::kScalar) return true;
    if (kind == Kind::kObject && items.size() > 6) return false;
    return std::all_of(items.begin(), items.end(),
                       [](const Node& n) { return n.kind == Kind::kScalar; });
  }
};

std::string json_string(const std::string& s, const char* what) {
  try {
    return Json(s).dump();
  } catch (const Json::type_error&) {
    throw std::invalid_argument(std::string(what) + " " + in_quotes(s) +
                                " is not valid UTF-8 (rule: JSON text is UTF-8)");
  }
}

void print(const Node& n, int indent, std::string& out);

// the items of an array or object, one line each at `indent` + 2
void print_items(const Node& n, int indent, std::string& out) {
  const std::string inner(static_cast<std::size_t>(indent) + 2, ' ');
  for (std::size_t i = 0; i < n.items.size(); ++i) {
    out += inner;
    if (n.kind == Node::Kind::kObject) out += Json(n.keys[i]).dump() + ": ";
    print(n.items[i], indent + 2, out);
    out += i + 1 < n.items.size() ? ",\n" : "\n";
  }
}

void print(const Node& n, int indent, std::string& out) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  if (n.kind == Node::Kind::kScalar) {
    out += n.text;
    return;
  }
  const bool is_array = n.kind == Node::Kind::kArray;
  const char open = is_array ? '[' : '{', close = is_array ? ']' : '}';
  if (n.items.empty()) {
    out += open;
    out += close;
  } else if (n.flat()) {
    out += open;
    for (std::size_t i = 0; i < n.items.size(); ++i) {
      if (i) out += ", ";
      if (!is_array) out += Json(n.keys[i]).dump() + ": ";
      out += n.items[i].text;
    }
    out += close;
  } else {
    out += open;
    out += '\n';
    print_items(n, indent, out);
    out += pad + close;
  }
}

Node number_node(double x) { return Node::scalar(json_number(x)); }
Node str(const std::string& s, const char* what) { return Node::scalar(json_string(s, what)); }
template <typename Vec>
Node vec(const Vec& v) {
  Node a = Node::array();
  for (int k = 0; k < v.size(); ++k) a.push(number_node(v[k]));
  return a;
}
Node quat(const Quaternion& q) { return vec(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z())); }
Node rows(const Matrix3& M) {
  Node a = Node::array();
  for (int r = 0; r < 3; ++r) a.push(vec(Eigen::Vector3d(M.row(r).transpose())));
  return a;
}
bool is_identity(const Quaternion& q) { return q.coeffs() == Quaternion::Identity().coeffs(); }

// {"xyz", "rotation"} of a transform; nullopt for the identity.
std::optional<Node> origin_node(const Transform& X) {
  Node o = Node::object();
  if (X.p != Vector3::Zero()) o.add("xyz", vec(X.p));
  if (X.R != Matrix3::Identity()) o.add("rotation", rows(X.R));
  if (o.empty()) return std::nullopt;
  return o;
}

Node inertial_node(const SpatialInertia& S) {
  const InertiaForm f = inertia_form(S);
  Node o = Node::object();
  o.add("mass", number_node(S.mass));
  if (f.com != Vector3::Zero()) o.add("com", vec(f.com));
  if (f.I == f.I.transpose()) {
    Node in = Node::object();
    in.add("ixx", number_node(f.I(0, 0)));
    in.add("iyy", number_node(f.I(1, 1)));
    in.add("izz", number_node(f.I(2, 2)));
    in.add("ixy", number_node(f.I(0, 1)));
    in.add("ixz", number_node(f.I(0, 2)));
    in.add("iyz", number_node(f.I(1, 2)));
    o.add("inertia", std::move(in));
  } else {
    o.add("inertia", rows(f.I));  // not symmetric to the last bit: all nine entries
  }
  return o;
}

Node geometry_node(const Geometry& g) {
  using S = Geometry::Shape;
  Node o = Node::object();
  o.add("shape", Node::scalar(Json(to_string(g.shape)).dump()));
  if (auto org = origin_node(g.X_LinkShape)) o.add("origin", std::move(*org));
  const bool uses_radius =
      g.shape == S::kSphere || g.shape == S::kCapsule || g.shape == S::kCylinder;
  const bool uses_length = g.shape == S::kCapsule || g.shape == S::kCylinder;
  // fields a shape does not use are written only when set, so nothing in the model is lost
  if (uses_radius || g.radius != 0) o.add("radius", number_node(g.radius));
  if (uses_length || g.length != 0) o.add("length", number_node(g.length));
  if (g.shape == S::kBox || g.size != Vector3::Zero()) o.add("size", vec(g.size));
  if (g.shape == S::kMesh || !g.mesh.empty()) o.add("mesh", str(g.mesh, "mesh path"));
  if (g.scale != Vector3::Ones()) o.add("scale", vec(g.scale));
  return o;
}

// "limits" of a 1-DOF joint; infinite bounds are left out (an omitted bound is unlimited)
std::optional<Node> limits_node(const JointLimits& L, const std::string& jname) {
  auto unrepresentable = [&](const char* what) {
    throw std::invalid_argument("joint " + in_quotes(jname) + ": " + what +
                                " cannot be written (rule: JSON numbers are finite; an "
                                "omitted lower limit is -inf, an omitted upper limit +inf)");
  };
  if (L.lower == kInfinity) unrepresentable("lower limit +inf");
  if (L.upper == -kInfinity) unrepresentable("upper limit -inf");
  if (L.velocity == -kInfinity || L.effort == -kInfinity) unrepresentable("a limit of -inf");
  Node l = Node::object();
  if (std::isfinite(L.lower)) l.add("lower", number_node(L.lower));
  if (std::isfinite(L.upper)) l.add("upper", number_node(L.upper));
  if (std::isfinite(L.velocity)) l.add("velocity", number_node(L.velocity));
  if (std::isfinite(L.effort)) l.add("effort", number_node(L.effort));
  if (l.empty()) return std::nullopt;
  return l;
}

Node range_node(const SphericalRange& r) {
  Node rn = Node::object();
  if (!is_identity(r.frame)) rn.add("frame", quat(r.frame));
  Node verts = Node::array();
  for (std::size_t k = 0; k < r.swing.size(); ++k) {
    const double lo = k < r.twist_lower.size() ? r.twist_lower[k] : 0.0;
    const double hi = k < r.twist_upper.size() ? r.twist_upper[k] : 0.0;
    verts.push(vec(Eigen::Vector4d(r.swing[k].x(), r.swing[k].y(), lo, hi)));
  }
  rn.add("vertices", std::move(verts));
  Node tris = Node::array();
  for (const auto& t : r.triangles) {
    Node tri = Node::array();
    for (int idx : t) tri.push(Node::scalar(std::to_string(idx)));
    tris.push(std::move(tri));
  }
  rn.add("triangles", std::move(tris));
  return rn;
}

Node joint_node(const Model& m, int i) {
  const JointType type = m.joint_type[i];
  const std::string& jname = m.joint_name[i];
  Node j = Node::object();
  if (jname != m.link_name[i]) j.add("name", str(jname, "joint name"));
  j.add("type", Node::scalar(Json(to_string(type)).dump()));
  if (auto org = origin_node(m.X_PJ[i])) j.add("origin", std::move(*org));
  if (one_dof(type)) {
    j.add("axis", vec(m.axis[i]));
    if (auto l = limits_node(m.limits[i], jname)) j.add("limits", std::move(*l));
  }
  if (type == JointType::kSpherical) {
    const SphericalRange& r = m.spherical_range[i];
    if (!is_identity(r.frame) || !r.swing.empty() || !r.triangles.empty()) {
      j.add("range", range_node(r));
    }
    if (!is_identity(m.standard_orientation[i])) {
      j.add("standard_orientation", quat(m.standard_orientation[i]));
    }
  }
  const double weight = m.ik_weight[i];
  if (weight != 1.0 || m.ik_gain[i]) {
    Node ik = Node::object();
    if (weight != 1.0) ik.add("weight", number_node(weight));
    if (m.ik_gain[i]) ik.add("gain", number_node(*m.ik_gain[i]));
    j.add("ik", std::move(ik));
  }
  return j;
}

Node link_node(const Model& m, int i) {
  Node l = Node::object();
  l.add("name", str(m.link_name[i], "link name"));
  if (m.parent[i] > 0) l.add("parent", str(m.link_name[m.parent[i]], "link name"));
  if (!m.display_name[i].empty()) l.add("display_name", str(m.display_name[i], "display name"));
  l.add("joint", joint_node(m, i));
  const SpatialInertia& S = m.inertia[i];
  if (S.mass != 0 || S.h != Vector3::Zero() || S.I_O != Matrix3::Zero()) {
    l.add("inertial", inertial_node(S));
  }
  for (const auto& [key, shapes] :
       {std::pair{"collision", &m.collision[i]}, std::pair{"visual", &m.visual[i]}}) {
    if (shapes->empty()) continue;
    Node arr = Node::array();
    for (const Geometry& g : *shapes) arr.push(geometry_node(g));
    l.add(key, std::move(arr));
  }
  return l;
}

}  // namespace

std::string write_character_json(const Model& m) {
  Node doc = Node::object();
  doc.add("format", Node::scalar(Json(kCharacterFormat).dump()));
  doc.add("version", Node::scalar(std::to_string(kCharacterFormatVersion)));
  doc.add("name", str(m.name, "model name"));
  doc.add("gravity", vec(m.gravity));
  Node links = Node::array();
  for (int i = 1; i < m.njoints; ++i) links.push(link_node(m, i));
  doc.add("links", std::move(links));
  std::string out;
  print(doc, 0, out);
  out += '\n';
  return out;
}

void save_character_json_file(const Model& model, const std::string& path) {
  write_file_atomically(path, write_character_json(model));
}

}  // namespace io
