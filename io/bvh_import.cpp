#include "io/bvh_import.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <unordered_set>

#include "core/configuration.hpp"
#include "io/bvh_parser.hpp"
#include "io/bvh_text.hpp"
#include "io/read_file.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using bvh_detail::kDegree;
using bvh_detail::num;

// a figure smaller than this (metres) has no extent: radii squared would underflow into links of
// mass without inertia
constexpr double kNoExtent = 1e-6;

[[noreturn]] void fail_import(const std::string& source, const std::string& what) {
  throw ModelError({source + ": " + what});
}

Quaternion elementary_quaternion(int axis, double radians) {
  const double h = 0.5 * radians;
  Quaternion q(std::cos(h), 0, 0, 0);
  q.coeffs()[axis] = std::sin(h);  // coeffs() is (x, y, z, w)
  return q;
}

// the joint's rotation channels, multiplied in file order
Quaternion joint_quaternion(const BvhNode& node, const double* v) {
  Quaternion q = Quaternion::Identity();
  for (std::size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (is_rotation(c)) q = q * elementary_quaternion(channel_axis(c), v[k] * kDegree);
  }
  return q.normalized();
}

bool has_position(const BvhNode& n) {
  return std::any_of(n.channels.begin(), n.channels.end(),
                     [](BvhChannel c) { return !is_rotation(c); });
}

// The rotation of the shortest arc from +Z to the direction of d (d != 0, finite): the unit
// quaternion proportional to (1 + u_z, z × u) with u = d / |d|. Near -Z, 1 + u_z is taken as
// (u_x² + u_y²) / (1 - u_z), free of cancellation; Eigen's FromTwoVectors loses it there and
// returns quaternions up to 1e-6 off unit length, whose matrices the model builder refuses as not
// orthonormal. Both vectors are scaled by their largest component first, so neither a 1e9 nor a
// denormal component under- or overflows. Exactly -Z: a half turn about X.
Matrix3 rotation_from_z(const Vector3& d) {
  const Vector3 a = d / d.cwiseAbs().maxCoeff();
  const Vector3 u = a / a.norm();  // |a| in [1, √3]
  const double w = u.z() >= 0 ? 1 + u.z() : (u.x() * u.x() + u.y() * u.y()) / (1 - u.z());
  Quaternion q(w, -u.y(), u.x(), 0);
  const double largest = q.coeffs().cwiseAbs().maxCoeff();
  if (!(largest > 0)) return Quaternion(0, 1, 0, 0).toRotationMatrix();
  q.coeffs() /= largest;
  q.normalize();
  return q.toRotationMatrix();
}

// Mass properties and collision shapes of a link of mass l.mass from the bones leaving its joint
// (metres, link frame): each bone a solid cylinder for the inertia and a capsule for collisions,
// `figure` the size that bounds the radii.
void add_bone_bodies(LinkSpec& l, const std::vector<Vector3>& bones, double figure) {
  const double tiny = 1e-9 * figure;
  double length = 0;
  for (const Vector3& d : bones) {
    const double L = d.norm();
    if (L > tiny) length += L;
  }
  if (length == 0) {  // no bone to speak of: a sphere at the joint
    const double r = 0.02 * figure;
    l.I_com = Matrix3::Identity() * (0.4 * l.mass * r * r);
    Geometry g;
    g.shape = Geometry::Shape::kSphere;
    g.radius = r;
    l.collision.push_back(g);
    return;
  }
  std::vector<double> mb;
  std::vector<Vector3> cb;
  std::vector<Matrix3> Ib;
  for (const Vector3& d : bones) {
    const double L = d.norm();
    if (L <= tiny) continue;
    const double m = l.mass * L / length;
    const double r = std::clamp(0.12 * L, 0.01 * figure, 0.05 * figure);
    const Vector3 u = d / L;
    // solid cylinder about its centre: axial m r²/2, across m (3r² + L²)/12
    const double axial = 0.5 * m * r * r;
    const double perp = m * (3 * r * r + L * L) / 12.0;
    mb.push_back(m);
    cb.push_back(0.5 * d);
    Ib.push_back(perp * Matrix3::Identity() + (axial - perp) * u * u.transpose());
    Geometry g;
    g.shape = Geometry::Shape::kCapsule;
    g.radius = r;
    g.length = L;
    g.X_LinkShape = {rotation_from_z(d), 0.5 * d};
    l.collision.push_back(g);
  }
  // combined about the common centre of mass (parallel axis theorem)
  Vector3 com = Vector3::Zero();
  for (std::size_t k = 0; k < mb.size(); ++k) com += mb[k] * cb[k];
  com /= l.mass;
  Matrix3 I = Matrix3::Zero();
  for (std::size_t k = 0; k < mb.size(); ++k) {
    const Vector3 e = cb[k] - com;
    I += Ib[k] + mb[k] * (e.squaredNorm() * Matrix3::Identity() - e * e.transpose());
  }
  l.com = com;
  l.I_com = 0.5 * (I + I.transpose());
}

// link names: the joint names, End Sites "<joint>_end" made unique
std::vector<std::string> link_names(const BvhDocument& doc) {
  const std::size_t n = doc.nodes.size();
  std::vector<std::string> link_name(n);
  std::unordered_set<std::string> used;
  for (const BvhNode& node : doc.nodes) {
    if (!node.is_end_site()) used.insert(node.name);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const BvhNode& node = doc.nodes[i];
    if (!node.is_end_site()) {
      link_name[i] = node.name;
      continue;
    }
    const std::string base = doc.nodes[node.parent].name + "_end";
    std::string name = base;
    for (int k = 2; used.count(name); ++k) name = base + "_" + std::to_string(k);
    used.insert(name);
    link_name[i] = name;
  }
  return link_name;
}

// Where each node's joint sits in its parent's frame (file units) and whether a non-root joint
// with position channels becomes rotational because its translation is constant over the frames
// to within kBvhConstantTranslationTolerance · figure (metres; `s` metres per file unit). The
// constant is the midrange of each component, which makes the largest deviation the smallest.
struct JointOrigins {
  std::vector<Vector3> origin;  // OFFSET, or the constant translation of a rotational joint
  std::vector<char> rotational;
};

JointOrigins joint_origins(const BvhDocument& doc,
                           const std::vector<std::string>& link_name,
                           const std::string& source_name,
                           const Model* joint_types_of,
                           double s,
                           double figure) {
  const std::size_t n = doc.nodes.size();
  JointOrigins out;
  out.origin.resize(n);
  out.rotational.assign(n, 0);
  std::vector<int> candidates;
  for (std::size_t i = 0; i < n; ++i) {
    const BvhNode& node = doc.nodes[i];
    out.origin[i] = node.offset;
    if (node.parent >= 0 && !node.is_end_site() && has_position(node) && doc.frames > 0) {
      candidates.push_back(static_cast<int>(i));
    }
  }
  if (candidates.empty()) return out;
  std::vector<Vector3> lo(candidates.size(), Vector3::Constant(kInfinity));
  std::vector<Vector3> hi(candidates.size(), Vector3::Constant(-kInfinity));
  for (int f = 0; f < doc.frames; ++f) {
    const double* values = doc.frame(f);
    for (std::size_t k = 0; k < candidates.size(); ++k) {
      const BvhNode& node = doc.nodes[candidates[k]];
      const Vector3 t = bvh_joint_translation(node, values + node.first_value);
      lo[k] = lo[k].cwiseMin(t);
      hi[k] = hi[k].cwiseMax(t);
    }
  }
  const double tolerance = kBvhConstantTranslationTolerance * figure;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    // values are finite and at most kMaxBvhMagnitude: no overflow
    const bool constant = 0.5 * (hi[k] - lo[k]).maxCoeff() * s <= tolerance;
    if (joint_types_of) {
      const int link = joint_types_of->link_index(link_name[candidates[k]]);
      if (link > 0 && joint_types_of->joint_type[link] == JointType::kFree) continue;
      if (link > 0 && !constant) {
        fail_import(source_name,
                    "joint \"" + doc.nodes[candidates[k]].name +
                        "\" translates in this clip, but the character it is loaded onto "
                        "has it rotational (rule: a joint's position channels may move only "
                        "where the character's joint is free)");
      }
    }
    if (!constant) continue;
    out.rotational[candidates[k]] = 1;
    out.origin[candidates[k]] = 0.5 * (lo[k] + hi[k]);
  }
  return out;
}

// The skeleton as a model: `s` metres per file unit, `figure` the size for the radii.
std::shared_ptr<const Model> build_model(const BvhDocument& doc,
                                         const std::string& source_name,
                                         const std::vector<std::string>& link_name,
                                         const JointOrigins& joints,
                                         double s,
                                         double figure,
                                         double total_mass) {
  // bones: from each joint to its children's OFFSETs (also for a child at a constant translation:
  // the figure's size, which bounds the radii, is that of the OFFSETs); mass in proportion to
  // their length
  const int n = static_cast<int>(doc.nodes.size());
  std::vector<std::vector<Vector3>> bones(n);
  for (int i = 1; i < n; ++i) bones[doc.nodes[i].parent].push_back(doc.nodes[i].offset * s);
  std::vector<double> weight(n, 0.0);
  double total_weight = 0;
  for (int i = 0; i < n; ++i) {
    if (doc.nodes[i].is_end_site()) continue;
    double length = 0;
    for (const Vector3& d : bones[i]) length += d.norm();
    weight[i] = std::max(length, 0.02 * figure);
    total_weight += weight[i];
  }

  ModelBuilder builder(std::filesystem::path(source_name).stem().string());
  for (int i = 0; i < n; ++i) {
    const BvhNode& node = doc.nodes[i];
    LinkSpec l;
    l.name = link_name[i];
    l.parent = node.parent < 0 ? "" : link_name[node.parent];
    l.joint.X_PJ = Transform::from_translation(joints.origin[i] * s);
    if (node.is_end_site()) {
      l.joint.type = JointType::kFixed;
    } else if (node.parent < 0 || (has_position(node) && !joints.rotational[i])) {
      l.joint.type = JointType::kFree;
    } else {
      l.joint.type = JointType::kSpherical;  // also with fewer than 3 rotation channels, or none
    }
    if (!node.is_end_site()) {
      l.mass = total_mass * weight[i] / total_weight;
      add_bone_bodies(l, bones[i], figure);
    }
    builder.add_link(std::move(l));
  }
  try {
    return builder.finalize();
  } catch (const ModelError& e) {
    std::vector<std::string> v;
    for (const std::string& line : e.violations()) v.push_back(source_name + ": " + line);
    throw ModelError(v);
  }
}

// out.layout, out.node_link and out.clip (one configuration per frame) for out.model
void import_motion(const BvhDocument& doc,
                   const std::vector<std::string>& link_name,
                   double s,
                   const BvhImportOptions& options,
                   BvhImport& out) {
  const Model& m = *out.model;
  struct JointMap {
    const BvhNode* node;
    int iq;
    JointType type;
  };
  std::vector<JointMap> joints;
  const int n = static_cast<int>(doc.nodes.size());
  out.node_link.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    const int link = m.link_index(link_name[i]);
    out.node_link[i] = link;
    const BvhNode& node = doc.nodes[i];
    if (node.is_end_site()) continue;
    out.layout.joints.push_back({node.name, node.channels});
    if (m.joint_type[link] == JointType::kFixed) continue;
    joints.push_back({&node, m.idx_q[link], m.joint_type[link]});
  }
  out.layout.scale = s;
  out.clip.frame_time = doc.frame_time;
  out.clip.frames.reserve(static_cast<std::size_t>(doc.frames));
  const Eigen::VectorXd neutral = neutral_configuration(m);
  const int step = std::max(1, doc.frames / 50);
  for (int f = 0; f < doc.frames; ++f) {
    Eigen::VectorXd q = neutral;
    const double* values = doc.frame(f);
    const Eigen::VectorXd* prev = f > 0 ? &out.clip.frames.back() : nullptr;
    for (const JointMap& j : joints) {
      const double* v = values + j.node->first_value;
      const int iq_rot = j.type == JointType::kFree ? j.iq + 3 : j.iq;
      Quaternion r = joint_quaternion(*j.node, v);
      // keep the quaternion on the previous frame's hemisphere
      if (prev && quaternion_at(*prev, iq_rot).coeffs().dot(r.coeffs()) < 0) r.coeffs() *= -1;
      set_quaternion_at(q, iq_rot, r);
      if (j.type == JointType::kFree) {
        q.segment<3>(j.iq) = (bvh_joint_translation(*j.node, v) - j.node->offset) * s;
      }
    }
    out.clip.frames.push_back(std::move(q));
    if (options.progress && f % step == 0) options.progress(static_cast<double>(f) / doc.frames);
  }
  if (options.progress) options.progress(1.0);
}

}  // namespace

namespace {

// the units a BVH file is read in: by key (the page and options), scale and name
struct Candidate {
  const char* key;
  double scale;
  const char* unit;
};
constexpr Candidate kUnitCandidates[] = {{"m", 1.0, "metres"},
                                         {"cm", 0.01, "centimetres"},
                                         {"mm", 0.001, "millimetres"},
                                         {"in", 0.0254, "inches"},
                                         {"cmu", kCmuUnit, "CMU units (1/0.45 inch)"}};

}  // namespace

std::optional<double> parse_bvh_import_unit(std::string_view name, std::string_view field) {
  if (name.empty() || bvh_detail::iequals(name, "auto")) return std::nullopt;
  for (const Candidate& c : kUnitCandidates) {
    if (bvh_detail::iequals(name, c.key)) return c.scale;
  }
  throw std::invalid_argument(std::string(field) + ": '" + std::string(name) +
                              "' (rule: one of auto, m, cm, mm, in, cmu)");
}

std::string bvh_unit_name(double scale) {
  for (const Candidate& c : kUnitCandidates) {
    if (scale == c.scale) return c.unit;
  }
  return num(scale) + " m per unit";
}

BvhUnit bvh_auto_scale(const BvhDocument& doc) {
  const double size = bvh_rest_extent(doc).largest;
  if (!(size > 0) || !std::isfinite(size)) return {1.0, "metres (the skeleton has no extent)"};
  constexpr double kTypical = 1.7;  // metres, a standing adult or an arm span
  BvhUnit best{1.0, ""};
  double best_error = kInfinity;
  for (const Candidate& c : kUnitCandidates) {
    const double error = std::abs(std::log(size * c.scale / kTypical));
    if (error < best_error) {
      best_error = error;
      best = {c.scale, c.unit};
    }
  }
  return best;
}

const BvhLayout::Joint* BvhLayout::find(std::string_view name) const {
  for (const Joint& j : joints) {
    if (j.name == name) return &j;
  }
  return nullptr;
}

BvhTranslationJoints bvh_translation_joints(const Model& model, const BvhLayout& layout) {
  BvhTranslationJoints out;
  for (std::size_t k = 1; k < layout.joints.size(); ++k) {  // joints[0] is the ROOT
    const BvhLayout::Joint& j = layout.joints[k];
    if (std::all_of(j.channels.begin(), j.channels.end(), is_rotation)) continue;
    const int link = model.link_index(j.name);
    if (link < 1) continue;
    (model.joint_type[link] == JointType::kFree ? out.translating : out.constant).push_back(j.name);
  }
  return out;
}

BvhImport import_bvh(const BvhDocument& doc,
                     const std::string& source_name,
                     const BvhImportOptions& options) {
  if (doc.nodes.empty()) fail_import(source_name, "the hierarchy has no joints");
  if (!std::isfinite(options.total_mass) || options.total_mass <= 0) {
    fail_import(source_name,
                "total mass " + num(options.total_mass) + " is not a positive finite number");
  }
  BvhImport out;
  double s = 1.0;
  if (options.scale) {
    s = *options.scale;
    if (!std::isfinite(s) || s <= 0) {
      fail_import(source_name,
                  "scale " + num(s) + " is not a positive finite number (metres per file unit)");
    }
    out.unit = "option";
  } else {
    const BvhUnit u = bvh_auto_scale(doc);
    s = u.scale;
    out.unit = u.unit;
  }
  const BvhExtent extent = bvh_rest_extent(doc);
  out.height = extent.height * s;
  const double figure = extent.largest * s > kNoExtent ? extent.largest * s : 1.0;
  const std::vector<std::string> link_name = link_names(doc);
  const JointOrigins joints =
      joint_origins(doc, link_name, source_name, options.joint_types_of, s, figure);
  out.model = build_model(doc, source_name, link_name, joints, s, figure, options.total_mass);
  import_motion(doc, link_name, s, options, out);
  BvhTranslationJoints moved = bvh_translation_joints(*out.model, out.layout);
  out.constant_translation_joints = std::move(moved.constant);
  out.translating_joints = std::move(moved.translating);
  out.warnings = doc.warnings;
  return out;
}

BvhImport load_bvh_string(std::string_view text,
                          const std::string& source_name,
                          const BvhImportOptions& options) {
  if (text.size() > kMaxBvhBytes) {
    fail_import(source_name, std::to_string(text.size()) + " bytes (rule: at most " +
                                 std::to_string(kMaxBvhBytes) + " bytes, kMaxBvhBytes)");
  }
  return import_bvh(parse_bvh(text, source_name, options.budget), source_name, options);
}

BvhImport load_bvh_file(const std::string& path, const BvhImportOptions& options) {
  std::string text;
  try {
    text = read_file(path, kMaxBvhBytes, "a BVH file");
  } catch (const FileError& e) {
    throw ModelError({e.what()});
  }
  return load_bvh_string(text, path, options);
}

}  // namespace io
