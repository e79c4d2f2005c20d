#include "io/gltf.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <system_error>
#include <unordered_set>

#include "io/atomic_file.hpp"
#include "core/clip.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

using Json = nlohmann::ordered_json;

// glTF enumerations (Specification §5: accessor.componentType, bufferView.target)
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;
// GLB container (Specification §4.4)
constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kGlbVersion = 2;
constexpr std::uint32_t kChunkJson = 0x4E4F534A;     // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;      // "BIN\0"
// a rotation that far from orthonormal is not a placement or a bind pose
constexpr double kRotationTolerance = 1e-6;

// ---------------------------------------------------------------------------------------------
// the binary buffer: views aligned to 4 bytes, accessors with exact bounds

class BufferBuilder {
 public:
  // appends a view (padded so the next one starts on a 4-byte boundary); returns its index
  int add_view(const void* bytes, size_t size, int target) {
    const size_t offset = data_.size();
    data_.resize(offset + size);
    if (size > 0) std::memcpy(data_.data() + offset, bytes, size);
    data_.resize((data_.size() + 3) & ~size_t{3}, 0);
    Json v = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
    if (target != 0) v["target"] = target;
    views_.push_back(std::move(v));
    return static_cast<int>(views_.size()) - 1;
  }

  // float accessor of `count` elements of `ncomp` components; min/max optional
  int add_floats(const std::vector<float>& values, int ncomp, const char* type, bool bounds,
                 int target) {
    const size_t count = values.size() / static_cast<size_t>(ncomp);
    const int view = add_view(values.data(), values.size() * sizeof(float), target);
    Json a = {{"bufferView", view}, {"componentType", kFloat}, {"count", count}, {"type", type}};
    if (bounds) {
      std::vector<float> lo(ncomp, std::numeric_limits<float>::infinity());
      std::vector<float> hi(ncomp, -std::numeric_limits<float>::infinity());
      for (size_t k = 0; k < count; ++k) {
        for (int c = 0; c < ncomp; ++c) {
          lo[c] = std::min(lo[c], values[k * ncomp + c]);
          hi[c] = std::max(hi[c], values[k * ncomp + c]);
        }
      }
      // the float values exactly, promoted to double, so the validator finds them equal
      Json jlo = Json::array(), jhi = Json::array();
      for (int c = 0; c < ncomp; ++c) {
        jlo.push_back(static_cast<double>(lo[c]));
        jhi.push_back(static_cast<double>(hi[c]));
      }
      a["min"] = std::move(jlo);
      a["max"] = std::move(jhi);
    }
    accessors_.push_back(std::move(a));
    return static_cast<int>(accessors_.size()) - 1;
  }

  template <typename T>
  int add_integers(const std::vector<T>& values, int component_type, const char* type,
                   size_t count, int target) {
    const int view = add_view(values.data(), values.size() * sizeof(T), target);
    accessors_.push_back(
        {{"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}});
    return static_cast<int>(accessors_.size()) - 1;
  }

  const std::vector<std::uint8_t>& data() const { return data_; }
  Json& views() { return views_; }
  Json& accessors() { return accessors_; }

 private:
  std::vector<std::uint8_t> data_;
  Json views_ = Json::array();
  Json accessors_ = Json::array();
};

// ---------------------------------------------------------------------------------------------
// small helpers

std::string base64(const std::vector<std::uint8_t>& in) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t v = (in[i] << 16) | (in[i + 1] << 8) | in[i + 2];
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += alphabet[v & 63];
  }
  if (i + 1 == in.size()) {
    const std::uint32_t v = in[i] << 16;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += "==";
  } else if (i + 2 == in.size()) {
    const std::uint32_t v = (in[i] << 16) | (in[i + 1] << 8);
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += alphabet[(v >> 6) & 63];
    out += '=';
  }
  return out;
}

// three.js binds animation tracks by sanitized node name: keep names to [A-Za-z0-9_] and unique
std::vector<std::string> node_names(const Model& model) {
  std::vector<std::string> names(model.njoints);
  std::unordered_set<std::string> used;
  for (int i = 1; i < model.njoints; ++i) {
    std::string s = model.link_name[i];
    for (char& c : s) {
      const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
      if (!ok) c = '_';
    }
    if (s.empty()) s = "link";
    std::string unique = s;
    for (int k = 2; used.count(unique) != 0; ++k) unique = s + "_" + std::to_string(k);
    used.insert(unique);
    names[i] = unique;
  }
  return names;
}

Json vec3(const Vector3& v) { return Json::array({v.x(), v.y(), v.z()}); }
// glTF quaternion order is (x, y, z, w)
Json quat(const Quaternion& q) { return Json::array({q.x(), q.y(), q.z(), q.w()}); }

bool is_rotation(const Matrix3& R) {
  return R.allFinite() && (R.transpose() * R - Matrix3::Identity()).norm() < kRotationTolerance &&
         R.determinant() > 0;
}

// column-major 4x4 of a rigid transform, as a glTF MAT4 (bottom row exactly 0 0 0 1)
void append_mat4(const Transform& X, std::vector<float>& out) {
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) out.push_back(static_cast<float>(X.R(r, c)));
    out.push_back(0.0f);
  }
  for (int r = 0; r < 3; ++r) out.push_back(static_cast<float>(X.p[r]));
  out.push_back(1.0f);
}

// the rotation and translation of joint i's frame in its parent for configuration q, computed
// as forward_kinematics does (joint_transform), with the rotation as an exact quaternion product
struct LocalPose {
  Quaternion rotation;
  Vector3 translation;
};
LocalPose local_pose(const Model& model, const std::vector<Quaternion>& placement, int i,
                     const Eigen::VectorXd& q) {
  const int iq = model.idx_q[i];
  const Transform& X = model.X_PJ[i];
  switch (model.joint_type[i]) {
    case JointType::kFixed: return {placement[i], X.p};
    case JointType::kRevolute:
      return {placement[i] * Quaternion(Eigen::AngleAxisd(q[iq], model.axis[i])), X.p};
    case JointType::kPrismatic: return {placement[i], X.p + X.R * (model.axis[i] * q[iq])};
    case JointType::kSpherical: return {placement[i] * quaternion_at(q, iq), X.p};
    case JointType::kFree:
      return {placement[i] * quaternion_at(q, iq + 3), X.p + X.R * q.segment<3>(iq)};
  }
  return {placement[i], X.p};
}

bool animates_rotation(JointType t) {
  return t == JointType::kRevolute || t == JointType::kSpherical || t == JointType::kFree;
}
bool animates_translation(JointType t) {
  return t == JointType::kPrismatic || t == JointType::kFree;
}

void check_skin(const Model& model, const SkinnedMesh& skin) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("glTF export: skinned mesh: " + what);
  };
  const size_t n = skin.positions.size();
  if (n > std::numeric_limits<std::uint32_t>::max()) fail("too many vertices");
  if (!skin.normals.empty() && skin.normals.size() != n) {
    fail(std::to_string(skin.normals.size()) + " normals for " + std::to_string(n) + " vertices");
  }
  if (skin.joints.size() != n || skin.weights.size() != n) {
    fail(std::to_string(skin.joints.size()) + " joint and " + std::to_string(skin.weights.size()) +
         " weight entries for " + std::to_string(n) + " vertices (rule: one of each per vertex)");
  }
  if (skin.inverse_bind.size() != skin.bones.size()) {
    fail(std::to_string(skin.inverse_bind.size()) + " inverse bind matrices for " +
         std::to_string(skin.bones.size()) + " bones");
  }
  std::vector<char> seen(model.njoints, 0);
  for (size_t b = 0; b < skin.bones.size(); ++b) {
    const int link = skin.bones[b];
    if (link < 1 || link >= model.njoints) {
      fail("bone " + std::to_string(b) + " refers to link " + std::to_string(link) +
           ", which the model does not have");
    }
    if (seen[link]++) fail("bone " + std::to_string(b) + ": link '" + model.link_name[link] +
                           "' is bound twice");
    if (!is_rotation(skin.inverse_bind[b].R) || !skin.inverse_bind[b].p.allFinite()) {
      fail("bone " + std::to_string(b) + " ('" + model.link_name[link] +
           "'): inverse bind matrix is not a finite rigid transform");
    }
  }
  for (size_t v = 0; v < n; ++v) {
    const std::string at = "vertex " + std::to_string(v) + ": ";
    if (!skin.positions[v].allFinite()) fail(at + "position is not finite");
    if (!skin.normals.empty() && !skin.normals[v].allFinite()) fail(at + "normal is not finite");
    float sum = 0;
    for (int k = 0; k < 4; ++k) {
      const float w = skin.weights[v][k];
      if (!std::isfinite(w) || w < 0) fail(at + "weight is negative or not finite");
      if (w > 0 && (skin.joints[v][k] < 0 ||
                    static_cast<size_t>(skin.joints[v][k]) >= skin.bones.size())) {
        fail(at + "joint index " + std::to_string(skin.joints[v][k]) + " is not a bone");
      }
      sum += w;
    }
    if (!(sum > 0)) fail(at + "weights sum to zero");
  }
  for (size_t t = 0; t < skin.triangles.size(); ++t) {
    for (int c : skin.triangles[t]) {
      if (c < 0 || static_cast<size_t>(c) >= n) {
        fail("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(c) +
             ", which does not exist");
      }
    }
  }
}

// unit normals: the given ones, else area-weighted face normals; +Y where neither is defined
std::vector<Eigen::Vector3f> unit_normals(const SkinnedMesh& skin) {
  const size_t n = skin.positions.size();
  std::vector<Eigen::Vector3d> acc(n, Eigen::Vector3d::Zero());
  for (const auto& t : skin.triangles) {
    const Eigen::Vector3d a = skin.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = skin.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = skin.positions[t[2]].cast<double>();
    const Eigen::Vector3d f = (b - a).cross(c - a);
    for (int k : t) acc[k] += f;
  }
  std::vector<Eigen::Vector3f> out(n);
  for (size_t v = 0; v < n; ++v) {
    Eigen::Vector3d m = skin.normals.empty() ? Eigen::Vector3d::Zero()
                                             : Eigen::Vector3d(skin.normals[v].cast<double>());
    if (!(m.norm() > 1e-12)) m = acc[v];
    if (!(m.norm() > 1e-20)) m = Eigen::Vector3d::UnitY();
    out[v] = m.normalized().cast<float>();
  }
  return out;
}

// four (joint, weight) pairs: duplicates merged, normalized so the float weights sum to 1 as
// closely as float allows (the residual goes to the largest weight), unused slots (0, 0)
void normalized_influences(const std::array<int, 4>& joints, const std::array<float, 4>& weights,
                           const std::vector<int>& skin_joint_of_bone, std::uint16_t* j_out,
                           float* w_out) {
  std::array<int, 4> j{0, 0, 0, 0};
  std::array<double, 4> w{0, 0, 0, 0};
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    if (!(weights[k] > 0)) continue;
    const int sj = skin_joint_of_bone[joints[k]];
    int slot = 0;
    while (slot < n && j[slot] != sj) ++slot;
    if (slot == n) j[n++] = sj;
    w[slot] += weights[k];
  }
  double total = 0;
  for (int k = 0; k < n; ++k) total += w[k];
  int largest = 0;
  for (int k = 0; k < n; ++k) {
    w[k] /= total;
    if (w[k] > w[largest]) largest = k;
  }
  double rest = 1.0;
  for (int k = 0; k < 4; ++k) {
    j_out[k] = static_cast<std::uint16_t>(k < n ? j[k] : 0);
    w_out[k] = k < n ? static_cast<float>(w[k]) : 0.0f;
    if (k != largest) rest -= w_out[k];
  }
  w_out[largest] = static_cast<float>(rest);
}

// one box from a to b with half width r (a == b: a cube of half size r at a), its vertices
// placed by X and skinned rigidly to `joint`; flat faces, four vertices each
void append_box(const Transform& X, const Vector3& a, const Vector3& b, double r, int joint,
                std::vector<float>& pos, std::vector<float>& nrm, std::vector<std::uint16_t>& jnt,
                std::vector<std::uint32_t>& idx) {
  Vector3 d = b - a;
  const double len = d.norm();
  Vector3 a0 = a, b0 = b;
  if (len < 1e-9) {
    d = Vector3::UnitY();
    a0 = a - r * d;
    b0 = a + r * d;
  } else {
    d /= len;
  }
  // (u, w, d) is right-handed; a corner is (k_u, k_w, k_d) in {-1, 1}³: k_d picks a0 or b0
  const Vector3 u = d.unitOrthogonal();
  const Vector3 w = d.cross(u);
  const Eigen::Matrix3d basis = (Eigen::Matrix3d() << u, w, d).finished();
  // each face: outward normal n and in-plane axes e1, e2 with e1 × e2 = n, so the corners
  // (-1,-1), (1,-1), (1,1), (-1,1) in (e1, e2) run counter-clockwise seen from outside
  const Eigen::Vector3d U(1, 0, 0), W(0, 1, 0), D(0, 0, 1);
  const std::array<std::array<Eigen::Vector3d, 3>, 6> faces = {
      {{U, W, D}, {-U, D, W}, {W, D, U}, {-W, U, D}, {D, U, W}, {-D, W, U}}};
  for (const auto& f : faces) {
    const auto base = static_cast<std::uint32_t>(pos.size() / 3);
    const Vector3 n_W = X.R * (basis * f[0]);
    for (int c = 0; c < 4; ++c) {
      const double s1 = (c == 1 || c == 2) ? 1 : -1;
      const double s2 = c >= 2 ? 1 : -1;
      const Eigen::Vector3d k = f[0] + s1 * f[1] + s2 * f[2];
      const Vector3 p_W = X * Vector3((k[2] > 0 ? b0 : a0) + r * (k[0] * u + k[1] * w));
      for (int t = 0; t < 3; ++t) pos.push_back(static_cast<float>(p_W[t]));
      for (int t = 0; t < 3; ++t) nrm.push_back(static_cast<float>(n_W[t]));
      jnt.insert(jnt.end(), {static_cast<std::uint16_t>(joint), 0, 0, 0});
    }
    idx.insert(idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
}

// indices as unsigned short when they fit, else unsigned int
int add_indices(BufferBuilder& buf, const std::vector<std::uint32_t>& idx, size_t nverts) {
  if (nverts <= 65535) {
    std::vector<std::uint16_t> s(idx.begin(), idx.end());
    return buf.add_integers(s, kUnsignedShort, "SCALAR", s.size(), kElementArrayBuffer);
  }
  return buf.add_integers(idx, kUnsignedInt, "SCALAR", idx.size(), kElementArrayBuffer);
}

struct Document {
  Json json;
  std::vector<std::uint8_t> bin;
};

Document build(const Model& model, const Clip* clip, const SkinnedMesh* skin,
               const GltfExportOptions& options) {
  const int nlinks = model.nlinks();
  if (nlinks < 1) throw std::invalid_argument("glTF export: the model has no links");
  if (nlinks > 65535) throw std::invalid_argument("glTF export: more than 65535 links");
  if (clip != nullptr) {
    const std::string e = check_clip(model, *clip);
    if (!e.empty()) throw std::invalid_argument("glTF export: clip: " + e);
  }
  if (skin != nullptr && skin->empty()) skin = nullptr;
  if (skin != nullptr) check_skin(model, *skin);
  if (options.stick_figure && !(options.stick_radius > 0 && std::isfinite(options.stick_radius))) {
    throw std::invalid_argument("glTF export: stick_radius must be a finite number > 0");
  }

  BufferBuilder buf;
  const std::vector<std::string> names = node_names(model);
  const std::string name = options.name.empty() ? model.name : options.name;
  std::vector<Quaternion> placement(model.njoints);
  for (int i = 1; i < model.njoints; ++i) placement[i] = Quaternion(model.X_PJ[i].R).normalized();

  // nodes: link i is node i - 1, at the neutral configuration (the bind pose)
  const Eigen::VectorXd q0 = neutral_configuration(model);
  Data data(model);
  forward_kinematics(model, data, q0);
  Json nodes = Json::array();
  std::vector<Json> children(model.njoints, Json::array());
  for (int i = 2; i < model.njoints; ++i) {
    if (model.parent[i] >= 1) children[model.parent[i]].push_back(i - 1);
  }
  Json scene_nodes = Json::array();
  for (int i = 1; i < model.njoints; ++i) {
    const LocalPose X = local_pose(model, placement, i, q0);
    Json n = {{"name", names[i]}};
    if (!children[i].empty()) n["children"] = children[i];
    n["translation"] = vec3(X.translation);
    n["rotation"] = quat(X.rotation.normalized());
    if (names[i] != model.link_name[i]) n["extras"] = {{"link", model.link_name[i]}};
    nodes.push_back(std::move(n));
    if (model.parent[i] == 0) scene_nodes.push_back(i - 1);
  }

  // skin: every link; inverse bind from the neutral pose, or the mesh's own for its bones
  std::vector<Transform> inverse_bind(model.njoints);
  for (int i = 1; i < model.njoints; ++i) inverse_bind[i] = data.X_W[i].inverse();
  std::vector<int> skin_joint_of_bone;
  if (skin != nullptr) {
    for (size_t b = 0; b < skin->bones.size(); ++b) {
      inverse_bind[skin->bones[b]] = skin->inverse_bind[b];
      skin_joint_of_bone.push_back(skin->bones[b] - 1);
    }
  }
  std::vector<float> ibm;
  ibm.reserve(16 * nlinks);
  Json joints = Json::array();
  for (int i = 1; i < model.njoints; ++i) {
    append_mat4(inverse_bind[i], ibm);
    joints.push_back(i - 1);
  }
  const int ibm_accessor = buf.add_floats(ibm, 16, "MAT4", false, 0);
  Json skins = Json::array({{{"name", name + "_skeleton"},
                              {"inverseBindMatrices", ibm_accessor},
                              {"skeleton", scene_nodes[0]},
                              {"joints", std::move(joints)}}});

  Json meshes = Json::array();
  Json materials = Json::array();
  // the skinned mesh
  if (skin != nullptr) {
    const size_t n = skin->positions.size();
    std::vector<float> pos, nrm, wgt;
    std::vector<std::uint16_t> jnt(4 * n);
    pos.reserve(3 * n);
    nrm.reserve(3 * n);
    wgt.resize(4 * n);
    const std::vector<Eigen::Vector3f> normals = unit_normals(*skin);
    for (size_t v = 0; v < n; ++v) {
      pos.insert(pos.end(), {skin->positions[v].x(), skin->positions[v].y(), skin->positions[v].z()});
      nrm.insert(nrm.end(), {normals[v].x(), normals[v].y(), normals[v].z()});
      normalized_influences(skin->joints[v], skin->weights[v], skin_joint_of_bone, &jnt[4 * v],
                            &wgt[4 * v]);
    }
    std::vector<std::uint32_t> idx;
    idx.reserve(3 * skin->triangles.size());
    for (const auto& t : skin->triangles) {
      idx.insert(idx.end(), {static_cast<std::uint32_t>(t[0]), static_cast<std::uint32_t>(t[1]),
                             static_cast<std::uint32_t>(t[2])});
    }
    Json attributes = {{"POSITION", buf.add_floats(pos, 3, "VEC3", true, kArrayBuffer)},
                       {"NORMAL", buf.add_floats(nrm, 3, "VEC3", false, kArrayBuffer)},
                       {"JOINTS_0", buf.add_integers(jnt, kUnsignedShort, "VEC4", n, kArrayBuffer)},
                       {"WEIGHTS_0", buf.add_floats(wgt, 4, "VEC4", false, kArrayBuffer)}};
    Json primitive = {{"attributes", std::move(attributes)}, {"material", materials.size()}};
    if (!idx.empty()) primitive["indices"] = add_indices(buf, idx, n);
    const Eigen::Vector4f c = skin->base_color.cwiseMax(0.0f).cwiseMin(1.0f);
    materials.push_back({{"name", skin->name.empty() ? "skin" : skin->name},
                         {"pbrMetallicRoughness",
                          {{"baseColorFactor", {c[0], c[1], c[2], c[3]}},
                           {"metallicFactor", 0.0},
                           {"roughnessFactor", 0.8}}}});
    meshes.push_back({{"name", skin->name.empty() ? "skin" : skin->name},
                      {"primitives", Json::array({std::move(primitive)})}});
  }
  // the stick figure: a box from each link to each child, a cube on each link origin
  if (options.stick_figure) {
    std::vector<float> pos, nrm;
    std::vector<std::uint16_t> jnt;
    std::vector<std::uint32_t> idx;
    const double r = options.stick_radius;
    for (int i = 1; i < model.njoints; ++i) {
      const Transform X_bind = inverse_bind[i].inverse();
      append_box(X_bind, Vector3::Zero(), Vector3::Zero(), 1.5 * r, i - 1, pos, nrm, jnt, idx);
      for (int c = i + 1; c < model.subtree_end[i]; ++c) {
        if (model.parent[c] != i) continue;
        append_box(X_bind, Vector3::Zero(), model.X_PJ[c].p, r, i - 1, pos, nrm, jnt, idx);
      }
    }
    const size_t n = pos.size() / 3;
    std::vector<float> wgt(4 * n, 0.0f);
    for (size_t v = 0; v < n; ++v) wgt[4 * v] = 1.0f;
    Json attributes = {{"POSITION", buf.add_floats(pos, 3, "VEC3", true, kArrayBuffer)},
                       {"NORMAL", buf.add_floats(nrm, 3, "VEC3", false, kArrayBuffer)},
                       {"JOINTS_0", buf.add_integers(jnt, kUnsignedShort, "VEC4", n, kArrayBuffer)},
                       {"WEIGHTS_0", buf.add_floats(wgt, 4, "VEC4", false, kArrayBuffer)}};
    Json primitive = {{"attributes", std::move(attributes)},
                      {"indices", add_indices(buf, idx, n)},
                      {"material", materials.size()}};
    materials.push_back({{"name", "stick_figure"},
                         {"pbrMetallicRoughness",
                          {{"baseColorFactor", {0.55, 0.65, 0.8, 1.0}},
                           {"metallicFactor", 0.0},
                           {"roughnessFactor", 0.6}}}});
    meshes.push_back({{"name", "stick_figure"}, {"primitives", Json::array({std::move(primitive)})}});
  }
  // mesh nodes: roots with an identity transform, skinned by skin 0
  for (size_t m = 0; m < meshes.size(); ++m) {
    nodes.push_back({{"name", meshes[m]["name"]}, {"mesh", m}, {"skin", 0}});
    scene_nodes.push_back(nodes.size() - 1);
  }

  // the animation: one LINEAR sampler per animated channel, one key per frame
  Json animations = Json::array();
  if (clip != nullptr && !clip->empty()) {
    const int nf = clip->size();
    std::vector<float> times(nf);
    for (int k = 0; k < nf; ++k) {
      times[k] = static_cast<float>(k * clip->frame_time);
      if (k > 0 && !(times[k] > times[k - 1])) {
        throw std::invalid_argument(
            "glTF export: frame time " + std::to_string(clip->frame_time) + " s is too short: " +
            "frames " + std::to_string(k - 1) + " and " + std::to_string(k) +
            " get the same single-precision key time (rule: key times strictly increase)");
      }
    }
    const int input = buf.add_floats(times, 1, "SCALAR", true, 0);
    Json samplers = Json::array(), channels = Json::array();
    std::vector<float> rot, tra;
    for (int i = 1; i < model.njoints; ++i) {
      const JointType t = model.joint_type[i];
      if (!animates_rotation(t) && !animates_translation(t)) continue;
      rot.clear();
      tra.clear();
      Quaternion prev(1, 0, 0, 0);
      for (int k = 0; k < nf; ++k) {
        const LocalPose X = local_pose(model, placement, i, clip->frames[k]);
        if (animates_rotation(t)) {
          Quaternion r = X.rotation.normalized();
          // hemisphere continuity: within 90° (4D) of the previous key, so slerp and
          // component-wise interpolation take the same short way
          if (k > 0 && r.coeffs().dot(prev.coeffs()) < 0) r.coeffs() = -r.coeffs();
          prev = r;
          rot.insert(rot.end(), {static_cast<float>(r.x()), static_cast<float>(r.y()),
                                 static_cast<float>(r.z()), static_cast<float>(r.w())});
        }
        if (animates_translation(t)) {
          tra.insert(tra.end(), {static_cast<float>(X.translation.x()),
                                 static_cast<float>(X.translation.y()),
                                 static_cast<float>(X.translation.z())});
        }
      }
      auto add_channel = [&](int output, const char* path) {
        channels.push_back({{"sampler", samplers.size()}, {"target", {{"node", i - 1}, {"path", path}}}});
        samplers.push_back({{"input", input}, {"output", output}, {"interpolation", "LINEAR"}});
      };
      if (animates_translation(t)) add_channel(buf.add_floats(tra, 3, "VEC3", false, 0), "translation");
      if (animates_rotation(t)) add_channel(buf.add_floats(rot, 4, "VEC4", false, 0), "rotation");
    }
    if (!channels.empty()) {
      animations.push_back(
          {{"name", name}, {"channels", std::move(channels)}, {"samplers", std::move(samplers)}});
    }
  }

  Document doc;
  Json& j = doc.json;
  j["asset"] = {{"version", "2.0"}, {"generator", options.generator}};
  j["scene"] = 0;
  j["scenes"] = Json::array({{{"name", name}, {"nodes", std::move(scene_nodes)}}});
  j["nodes"] = std::move(nodes);
  if (!meshes.empty()) {
    j["meshes"] = std::move(meshes);
    j["materials"] = std::move(materials);
  }
  j["skins"] = std::move(skins);
  if (!animations.empty()) j["animations"] = std::move(animations);
  j["accessors"] = std::move(buf.accessors());
  j["bufferViews"] = std::move(buf.views());
  j["buffers"] = Json::array({{{"byteLength", buf.data().size()}}});
  doc.bin = buf.data();
  return doc;
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<std::uint8_t>(v >> (8 * k)));
}

}  // namespace

std::string write_gltf(const Model& model,
                       const Clip* clip,
                       const SkinnedMesh* skin,
                       const GltfExportOptions& options) {
  Document doc = build(model, clip, skin, options);
  doc.json["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(doc.bin);
  return doc.json.dump(1) + "\n";
}

std::vector<std::uint8_t> write_glb(const Model& model,
                                    const Clip* clip,
                                    const SkinnedMesh* skin,
                                    const GltfExportOptions& options) {
  const Document doc = build(model, clip, skin, options);
  std::string json = doc.json.dump();
  json.resize((json.size() + 3) & ~size_t{3}, ' ');
  const size_t bin_size = (doc.bin.size() + 3) & ~size_t{3};
  const size_t total = 12 + 8 + json.size() + 8 + bin_size;
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("glTF export: the GLB would exceed 4 GiB");
  }
  std::vector<std::uint8_t> out;
  out.reserve(total);
  put_u32(out, kGlbMagic);
  put_u32(out, kGlbVersion);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(json.size()));
  put_u32(out, kChunkJson);
  out.insert(out.end(), json.begin(), json.end());
  put_u32(out, static_cast<std::uint32_t>(bin_size));
  put_u32(out, kChunkBin);
  out.insert(out.end(), doc.bin.begin(), doc.bin.end());
  out.resize(total, 0);
  return out;
}

void save_gltf_file(const std::string& path,
                    const Model& model,
                    const Clip* clip,
                    const SkinnedMesh* skin,
                    const GltfExportOptions& options) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  try {
    if (ext == ".gltf") {
      const std::string text = write_gltf(model, clip, skin, options);
      write_file_atomically(path, text.data(), text.size());
    } else if (ext == ".glb") {
      const std::vector<std::uint8_t> bytes = write_glb(model, clip, skin, options);
      write_file_atomically(path, bytes.data(), bytes.size());
    } else {
      throw std::invalid_argument("glTF export: unknown extension '" + ext +
                                  "' (rule: .gltf or .glb)");
    }
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

}  // namespace io
