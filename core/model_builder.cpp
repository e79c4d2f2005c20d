#include "core/model_builder.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>
#include <unordered_map>

#include "core/swing_twist.hpp"

namespace core {

namespace {

std::string join_lines(const std::vector<std::string>& lines) {
  std::string out;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (i) out += '\n';
    out += lines[i];
  }
  return out;
}

bool finite(const Eigen::Ref<const Eigen::MatrixXd>& m) { return m.allFinite(); }

std::string num(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

// Collects violations with a uniform "link 'x': ..." / "joint 'x': ..." prefix.
class Checker {
 public:
  void link(const std::string& name, const std::string& what) {
    out.push_back("link '" + name + "': " + what);
  }
  void joint(const std::string& name, const std::string& what) {
    out.push_back("joint '" + name + "': " + what);
  }
  void model(const std::string& what) { out.push_back(what); }
  std::vector<std::string> out;
};

bool is_rotation(const Matrix3& R) {
  return R.allFinite() && (R.transpose() * R - Matrix3::Identity()).norm() < 1e-6 &&
         R.determinant() > 0;
}

void check_inertia(const LinkSpec& l, Checker& c) {
  if (!std::isfinite(l.mass))
    c.link(l.name, "mass is not finite (rule: mass must be finite)");
  else if (l.mass < 0)
    c.link(l.name, "mass " + num(l.mass) + " is negative (rule: mass must be >= 0)");
  if (!finite(l.com)) c.link(l.name, "centre of mass is not finite");
  if (!finite(l.I_com)) {
    c.link(l.name, "inertia is not finite");
    return;
  }
  const Matrix3& I = l.I_com;
  const double scale = std::max(1e-12, I.cwiseAbs().maxCoeff());
  if ((I - I.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    c.link(l.name, "inertia is not symmetric");
    return;
  }
  const Eigen::Vector3d e = Eigen::SelfAdjointEigenSolver<Matrix3>(I).eigenvalues();
  const double tol = 1e-9 * scale;
  if (e.minCoeff() < -tol) {
    c.link(l.name, "inertia is not positive semidefinite (smallest principal moment " +
                       num(e.minCoeff()) + ")");
    return;
  }
  // principal moments of a real body satisfy I1 + I2 >= I3 (eigenvalues sorted ascending)
  if (e(0) + e(1) < e(2) - 1e-6 * scale) {
    c.link(l.name, "principal moments " + num(e(0)) + ", " + num(e(1)) + ", " + num(e(2)) +
                       " violate the triangle inequality (rule: I1 + I2 >= I3)");
  }
}

void check_geometry(const std::string& link,
                    const std::vector<Geometry>& shapes,
                    const char* kind,
                    Checker& c) {
  for (size_t k = 0; k < shapes.size(); ++k) {
    const Geometry& g = shapes[k];
    const std::string where =
        std::string(kind) + " shape " + std::to_string(k) + " (" + to_string(g.shape) + "): ";
    if (!is_rotation(g.X_LinkShape.R) || !finite(g.X_LinkShape.p)) {
      c.link(link, where + "pose is not a finite rigid transform");
    }
    const bool ok_sizes =
        std::isfinite(g.radius) && std::isfinite(g.length) && finite(g.size) && finite(g.scale);
    if (!ok_sizes) {
      c.link(link, where + "dimensions are not finite");
      continue;
    }
    switch (g.shape) {
      case Geometry::Shape::kSphere:
        if (g.radius <= 0) c.link(link, where + "radius must be > 0");
        break;
      case Geometry::Shape::kCapsule:
      case Geometry::Shape::kCylinder:
        if (g.radius <= 0) c.link(link, where + "radius must be > 0");
        if (g.length < 0) c.link(link, where + "length must be >= 0");
        break;
      case Geometry::Shape::kBox:
        if ((g.size.array() <= 0).any()) c.link(link, where + "box sizes must be > 0");
        break;
      case Geometry::Shape::kMesh:
        if (g.mesh.empty()) c.link(link, where + "mesh path is empty");
        break;
    }
  }
}

void check_spherical_range(const std::string& joint, const SphericalRange& r, Checker& c) {
  if (std::abs(r.frame.norm() - 1.0) > 1e-6 || !finite(r.frame.coeffs())) {
    c.joint(joint, "range frame is not a unit quaternion");
  }
  const size_t nvert = r.swing.size();
  if (r.twist_lower.size() != nvert || r.twist_upper.size() != nvert) {
    c.joint(joint, "range has " + std::to_string(nvert) +
                       " swing vertices but a different number of twist limits");
    return;
  }
  if (r.triangles.size() > static_cast<size_t>(kMaxRangeTriangles)) {
    c.joint(joint, "range has " + std::to_string(r.triangles.size()) +
                       " triangles (rule: at most " + std::to_string(kMaxRangeTriangles) + ")");
    return;
  }
  for (size_t k = 0; k < nvert; ++k) {
    const std::string v = "range vertex " + std::to_string(k) + ": ";
    if (!finite(r.swing[k]) || !std::isfinite(r.twist_lower[k]) ||
        !std::isfinite(r.twist_upper[k])) {
      c.joint(joint, v + "values are not finite");
    } else {
      if (r.swing[k].norm() > 1.0 + 1e-12) {
        c.joint(joint, v + "swing (a_y, a_z) lies outside the unit disk (rule: |a| <= 1)");
      }
      if (r.twist_lower[k] > r.twist_upper[k]) {
        c.joint(joint,
                v + "twist lower " + num(r.twist_lower[k]) + " > upper " + num(r.twist_upper[k]));
      }
    }
  }
  for (size_t t = 0; t < r.triangles.size(); ++t) {
    const auto& tri = r.triangles[t];
    bool ok = true;
    for (int idx : tri) ok = ok && idx >= 0 && static_cast<size_t>(idx) < nvert;
    if (!ok) {
      c.joint(joint, "range triangle " + std::to_string(t) + " refers to a missing vertex");
      continue;
    }
    const Eigen::Vector2d e1 = r.swing[tri[1]] - r.swing[tri[0]];
    const Eigen::Vector2d e2 = r.swing[tri[2]] - r.swing[tri[0]];
    if (std::abs(e1.x() * e2.y() - e1.y() * e2.x()) < 1e-12) {
      c.joint(joint, "range triangle " + std::to_string(t) + " has zero area");
    }
  }
}

void check_joint(const LinkSpec& l, const std::string& jname, bool is_root, Checker& c) {
  const JointSpec& j = l.joint;
  if (!is_rotation(j.X_PJ.R) || !finite(j.X_PJ.p)) {
    c.joint(jname, "placement is not a finite rigid transform (rotation must be orthonormal)");
  }
  const bool one_dof = j.type == JointType::kRevolute || j.type == JointType::kPrismatic;
  if (one_dof) {
    if (!finite(j.axis) || j.axis.norm() < 1e-9) {
      c.joint(jname, "axis must be finite and non-zero");
    }
    const JointLimits& L = j.limits;
    if (std::isnan(L.lower) || std::isnan(L.upper)) {
      c.joint(jname, "limit is NaN");
    } else if (L.lower > L.upper) {
      c.joint(jname, "lower limit " + num(L.lower) + " > upper limit " + num(L.upper) +
                         " (rule: lower <= upper)");
    }
    if (std::isnan(L.velocity) || L.velocity < 0 || std::isnan(L.effort) || L.effort < 0) {
      c.joint(jname, "velocity and effort limits must be >= 0");
    }
  }
  if (j.type == JointType::kSpherical) {
    check_spherical_range(jname, j.range, c);
    const Quaternion& s = j.standard_orientation;
    if (!finite(s.coeffs()) || std::abs(s.norm() - 1.0) > 1e-6) {
      c.joint(jname, "standard orientation is not a unit quaternion");
    }
  } else if (!j.range.empty()) {
    c.joint(jname, "has a swing-twist range but is not spherical");
  }
  if (!std::isfinite(j.ik_weight) || j.ik_weight < 0) {
    c.joint(jname, "IK weight must be finite and >= 0");
  }
  if (j.ik_gain && (!std::isfinite(*j.ik_gain) || *j.ik_gain < 0)) {
    c.joint(jname, "IK gain must be finite and >= 0");
  }
  if (j.type == JointType::kFree && !is_root) {
    // a free joint below the root is legal (a thrown prop), nothing to check
  }
}

}  // namespace

ModelError::ModelError(std::vector<std::string> violations)
    : std::runtime_error(join_lines(violations)), violations_(std::move(violations)) {}

int ModelBuilder::add_link(LinkSpec link) {
  if (static_cast<int>(links_.size()) >= kMaxLinks) {
    throw ModelError({"model has more than " + std::to_string(kMaxLinks) +
                      " links (rule: at most " + std::to_string(kMaxLinks) + ")"});
  }
  links_.push_back(std::move(link));
  return static_cast<int>(links_.size()) - 1;
}

std::shared_ptr<const Model> ModelBuilder::finalize() const {
  Checker c;
  const int n = static_cast<int>(links_.size());
  if (n == 0) throw ModelError({"model has no links"});
  if (!finite(gravity_)) c.model("gravity is not finite");

  // names: links and joints unique and non-empty
  std::unordered_map<std::string, int> link_by_name;
  std::unordered_map<std::string, int> joint_by_name;
  std::vector<std::string> joint_names(n);
  for (int i = 0; i < n; ++i) {
    const LinkSpec& l = links_[i];
    joint_names[i] = l.joint.name.empty() ? l.name : l.joint.name;
    if (l.name.empty())
      c.model("link #" + std::to_string(i) + " has an empty name");
    else if (!link_by_name.emplace(l.name, i).second)
      c.link(l.name, "name is used by more than one link (rule: link names are unique)");
    if (!joint_names[i].empty() && !joint_by_name.emplace(joint_names[i], i).second)
      c.joint(joint_names[i], "name is used by more than one joint (rule: joint names are unique)");
  }

  // topology: exactly one root, every parent exists
  std::vector<int> parent_of(n, -1);
  std::vector<int> roots;
  for (int i = 0; i < n; ++i) {
    const LinkSpec& l = links_[i];
    if (l.parent.empty()) {
      roots.push_back(i);
      continue;
    }
    auto it = link_by_name.find(l.parent);
    if (it == link_by_name.end()) {
      c.link(l.name, "parent link '" + l.parent + "' does not exist");
    } else if (it->second == i) {
      c.link(l.name, "is its own parent (rule: no cycles)");
    } else {
      parent_of[i] = it->second;
    }
  }
  if (roots.empty()) {
    c.model("model has no root link (rule: exactly one link has no parent)");
  } else if (roots.size() > 1) {
    std::string names;
    for (int r : roots) names += (names.empty() ? "'" : ", '") + links_[r].name + "'";
    c.model("model has " + std::to_string(roots.size()) + " root links " + names +
            " (rule: exactly one link has no parent)");
  }

  // depth-first order from the root, without recursion; links not reached lie on a cycle
  std::vector<std::vector<int>> children(n);
  for (int i = 0; i < n; ++i) {
    if (parent_of[i] >= 0) children[parent_of[i]].push_back(i);
  }
  std::vector<int> order;  // builder index of each model link, in depth-first order
  order.reserve(n);
  if (roots.size() == 1) {
    std::vector<int> stack{roots[0]};
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      order.push_back(i);
      for (auto it = children[i].rbegin(); it != children[i].rend(); ++it) stack.push_back(*it);
    }
  }
  if (roots.size() == 1 && static_cast<int>(order.size()) < n) {
    std::vector<bool> reached(n, false);
    for (int i : order) reached[i] = true;
    for (int i = 0; i < n; ++i) {
      if (!reached[i] && parent_of[i] >= 0) {
        c.link(links_[i].name, "lies on a cycle of parent links (rule: no cycles)");
      }
    }
  }

  for (int i = 0; i < n; ++i) {
    const LinkSpec& l = links_[i];
    check_joint(l, joint_names[i], l.parent.empty(), c);
    check_inertia(l, c);
    check_geometry(l.name, l.collision, "collision", c);
    check_geometry(l.name, l.visual, "visual", c);
  }
  if (!c.out.empty()) throw ModelError(c.out);

  // build
  auto m = std::make_shared<Model>();
  m->name = name_;
  m->gravity = gravity_;
  m->source_dir = source_dir_;
  const int nj = n + 1;
  m->njoints = nj;
  m->parent.assign(nj, -1);
  m->subtree_end.assign(nj, 0);
  m->link_name.assign(nj, "world");
  m->joint_name.assign(nj, "world");
  m->display_name.assign(nj, "");
  m->joint_type.assign(nj, JointType::kFixed);
  m->X_PJ.assign(nj, Transform::Identity());
  m->axis.assign(nj, Vector3::UnitZ());
  m->axis_index.assign(nj, -1);
  m->placement_is_translation.assign(nj, 1);
  m->idx_q.assign(nj, 0);
  m->idx_v.assign(nj, 0);
  m->limits.assign(nj, JointLimits{});
  m->spherical_range.assign(nj, SphericalRange{});
  m->range_inner.assign(nj, RangeInnerBounds{});
  m->standard_orientation.assign(nj, Quaternion::Identity());
  m->ik_weight.assign(nj, 1.0);
  m->ik_gain.assign(nj, std::nullopt);
  m->inertia.assign(nj, SpatialInertia::Zero());
  m->collision.assign(nj, {});
  m->visual.assign(nj, {});

  std::vector<int> model_index(n, -1);
  for (int k = 0; k < n; ++k) model_index[order[k]] = k + 1;
  int nq = 0;
  int nv = 0;
  for (int k = 0; k < n; ++k) {
    const LinkSpec& l = links_[order[k]];
    const JointSpec& j = l.joint;
    const int i = k + 1;
    m->parent[i] = parent_of[order[k]] < 0 ? 0 : model_index[parent_of[order[k]]];
    m->link_name[i] = l.name;
    m->joint_name[i] = joint_names[order[k]];
    m->display_name[i] = l.display_name;
    m->joint_type[i] = j.type;
    m->X_PJ[i] = j.X_PJ;
    m->placement_is_translation[i] = j.X_PJ.R == Matrix3::Identity() ? 1 : 0;
    if (j.type == JointType::kRevolute || j.type == JointType::kPrismatic) {
      m->axis[i] = j.axis.normalized();
      for (int a = 0; a < 3; ++a) {
        if (m->axis[i] == Vector3::Unit(a)) m->axis_index[i] = a;
      }
      m->limits[i] = j.limits;
    }
    if (j.type == JointType::kSpherical) {
      m->spherical_range[i] = j.range;
      m->spherical_range[i].frame.normalize();
      m->range_inner[i] = inner_bounds(m->spherical_range[i]);
      m->standard_orientation[i] = j.standard_orientation.normalized();
    }
    m->ik_weight[i] = j.ik_weight;
    m->ik_gain[i] = j.ik_gain;
    m->inertia[i] = SpatialInertia::from_com(l.mass, l.com, l.I_com);
    m->collision[i] = l.collision;
    m->visual[i] = l.visual;
    m->idx_q[i] = nq;
    m->idx_v[i] = nv;
    nq += joint_nq(j.type);
    nv += joint_nv(j.type);
  }
  m->nq = nq;
  m->nv = nv;
  m->joint_of_v.assign(nv, 0);
  m->parent_v.assign(nv, -1);
  for (int i = 1; i < nj; ++i) {
    const int nvi = joint_nv(m->joint_type[i]);
    if (nvi == 0) continue;
    // the first coordinate hangs from the last coordinate of the nearest moving ancestor
    int anc = m->parent[i];
    while (anc > 0 && joint_nv(m->joint_type[anc]) == 0) anc = m->parent[anc];
    const int first = m->idx_v[i];
    m->parent_v[first] = anc > 0 ? m->idx_v[anc] + joint_nv(m->joint_type[anc]) - 1 : -1;
    for (int d = 0; d < nvi; ++d) {
      m->joint_of_v[first + d] = i;
      if (d > 0) m->parent_v[first + d] = first + d - 1;
    }
  }
  m->chain_start_v.resize(nv);
  for (int k = 0; k < nv; ++k) {
    m->chain_start_v[k] = k > 0 && m->parent_v[k] == k - 1 ? m->chain_start_v[k - 1] : k;
  }
  // subtree ranges: in depth-first order a subtree ends where the next non-descendant starts
  for (int i = nj - 1; i >= 0; --i) {
    m->subtree_end[i] = std::max(m->subtree_end[i], i + 1);
    if (i > 0)
      m->subtree_end[m->parent[i]] = std::max(m->subtree_end[m->parent[i]], m->subtree_end[i]);
  }
  return m;
}

}  // namespace core
