#include "io/assimp_import.hpp"

#include <sys/stat.h>

#include <Eigen/SVD>
#include <algorithm>
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include "core/configuration.hpp"
#include "io/character_json.hpp"
#include "core/model_builder.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

namespace fs = std::filesystem;
using Matrix4 = Eigen::Matrix4d;

// the reply's first bytes: format and version of the child → parent wire format below
constexpr char kReplyMagic[8] = {'P', 'D', 'S', 'K', 'I', 'N', '0', '1'};
constexpr std::uint8_t kReplyOk = 0;
constexpr std::uint8_t kReplyError = 1;
// a node scale this far from 1 (after the unit scale) cannot be carried by a rigid link
constexpr double kScaleTolerance = 1e-3;
// most frames one clip may have after resampling
constexpr double kMaxFrames = 1e6;
// bytes of a file read to recognize its format
constexpr std::size_t kSniffBytes = 4096;

// ---------------------------------------------------------------------------------------------
// the wire format: little-endian scalars, strings as u32 length + bytes, arrays as u32 count +
// elements. The parent treats it as untrusted input: every read is bounds-checked.

class ReplyWriter {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) { raw(&v, 4); }
  void i32(std::int32_t v) { raw(&v, 4); }
  void f32(float v) { raw(&v, 4); }
  void f64(double v) { raw(&v, 8); }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    out_ += s;
  }
  void raw(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

class ReplyReader {
 public:
  explicit ReplyReader(const std::string& in) : in_(in) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(in_[at_++]);
  }
  std::uint32_t u32() { return scalar<std::uint32_t>(); }
  std::int32_t i32() { return scalar<std::int32_t>(); }
  float f32() { return scalar<float>(); }
  double f64() { return scalar<double>(); }
  std::string str(std::size_t max_len) {
    const std::uint32_t n = u32();
    if (n > max_len) throw std::runtime_error("a string of " + std::to_string(n) + " bytes");
    need(n);
    std::string s = in_.substr(at_, n);
    at_ += n;
    return s;
  }
  // a count of elements of `element_bytes` each that must fit in the rest of the reply
  std::size_t count(std::size_t element_bytes) {
    const std::uint32_t n = u32();
    if (static_cast<std::size_t>(n) * element_bytes > in_.size() - at_) {
      throw std::runtime_error("a count of " + std::to_string(n) + " that runs past the end");
    }
    return n;
  }
  bool at_end() const { return at_ == in_.size(); }
  void expect_magic() {
    need(sizeof kReplyMagic);
    if (std::memcmp(in_.data() + at_, kReplyMagic, sizeof kReplyMagic) != 0) {
      throw std::runtime_error("it does not start with the reply signature");
    }
    at_ += sizeof kReplyMagic;
  }

 private:
  template <typename T>
  T scalar() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, in_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  void need(std::size_t n) {
    if (in_.size() - at_ < n) throw std::runtime_error("it ends early, at byte " + std::to_string(at_));
  }
  const std::string& in_;
  std::size_t at_ = 0;
};

// ---------------------------------------------------------------------------------------------
// affine matrices and their rigid part

Matrix4 to_eigen(const aiMatrix4x4& m) {
  // aiMatrix4x4 is row-major: a1..a4 is the first row, the translation is (a4, b4, c4)
  Matrix4 e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return e;
}

Matrix4 trs(const Vector3& t, const Quaternion& r, const Vector3& s) {
  Matrix4 m = Matrix4::Identity();
  m.topLeftCorner<3, 3>() = r.toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

// the rotation nearest the linear part (polar decomposition) and the translation; `scale_error`
// gets the largest |σ − 1| of the linear part's singular values
Transform rigid(const Matrix4& M, double& scale_error) {
  const Matrix3 L = M.topLeftCorner<3, 3>();
  Eigen::JacobiSVD<Matrix3> svd(L, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3 U = svd.matrixU();
  const Matrix3 V = svd.matrixV();
  // the singular values are the diagonal of Uᵀ L V (read that way rather than through
  // singularValues(), where GCC 12 at -O3 reports a false -Wmaybe-uninitialized)
  const Vector3 sigma = (U.transpose() * L * V).diagonal();
  if ((U * V.transpose()).determinant() < 0) U.col(2) = -U.col(2);
  scale_error = (sigma.array() - 1.0).abs().maxCoeff();
  return {U * V.transpose(), M.topRightCorner<3, 1>()};
}

bool finite_matrix(const aiMatrix4x4& m) { return to_eigen(m).allFinite(); }

// ---------------------------------------------------------------------------------------------
// in the child: assimp's scene → our model, skinned mesh and clips

// Reads only files inside the folder of the imported file (a .gltf's buffers); refuses the rest.
class FolderIOSystem : public Assimp::DefaultIOSystem {
 public:
  explicit FolderIOSystem(fs::path folder) : folder_(std::move(folder)) {}
  bool Exists(const char* file) const override {
    return inside(file) && Assimp::DefaultIOSystem::Exists(file);
  }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!inside(file) || std::strchr(mode, 'w') != nullptr || std::strchr(mode, 'a') != nullptr) {
      return nullptr;
    }
    return Assimp::DefaultIOSystem::Open(file, mode);
  }

 private:
  bool inside(const char* file) const {
    std::error_code ec;
    const fs::path p = fs::weakly_canonical(fs::path(file), ec);
    if (ec) return false;
    const auto rel = p.lexically_relative(folder_);
    return !rel.empty() && *rel.begin() != ".." && !rel.is_absolute();
  }
  fs::path folder_;
};

struct Node {
  const aiNode* ai = nullptr;
  int parent = -1;
  int depth = 0;
  std::string name;
  Matrix4 local_rest = Matrix4::Identity();   // mTransformation
  Matrix4 global_rest = Matrix4::Identity();  // product from the scene root
  Vector3 rest_t = Vector3::Zero();           // mTransformation decomposed
  Quaternion rest_r = Quaternion::Identity();
  Vector3 rest_s = Vector3::Ones();
};

Vector3 key_value(const aiVectorKey& k) { return Vector3(k.mValue.x, k.mValue.y, k.mValue.z); }
Quaternion key_value(const aiQuatKey& k) {
  return Quaternion(k.mValue.w, k.mValue.x, k.mValue.y, k.mValue.z);
}

// key search and interpolation of one channel component; keys are sorted by time; without keys,
// the node's rest value
template <typename Key, typename V, typename Lerp>
V sample_keys(const Key* keys, unsigned n, double t, const V& rest, Lerp lerp) {
  if (n == 0) return rest;
  const Key* end = keys + n;
  const Key* hi = std::upper_bound(keys, end, t, [](double x, const Key& k) { return x < k.mTime; });
  if (hi == keys) return key_value(keys[0]);
  if (hi == end) return key_value(keys[n - 1]);
  const Key& a = *(hi - 1);
  const Key& b = *hi;
  const double span = b.mTime - a.mTime;
  if (!(span > 0)) return key_value(b);
  return lerp(key_value(a), key_value(b), (t - a.mTime) / span);
}

// a skinned triangle mesh of the file
struct SourceMesh {
  const aiMesh* mesh = nullptr;
  std::vector<int> bone_node;        // node of each aiBone, or -1
  Matrix4 B = Matrix4::Identity();   // bind space → file world (global × offset of any bone)
};

class Converter {
 public:
  Converter(const aiScene& scene, const std::string& path, const ImportOptions& options)
      : scene_(scene), source_(fs::path(path).filename().string()), options_(options) {
    ext_ = fs::path(path).extension().string();
    std::transform(ext_.begin(), ext_.end(), ext_.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    stem_ = fs::path(path).stem().string();
  }

  void run(ReplyWriter& w) {
    index_nodes();
    world_axes();
    collect_bones();
    choose_links();
    bind_poses();
    sample_offsets();
    build_model();
    build_mesh();
    build_clips();
    write(w);
  }

 private:
  // ---- nodes, depth-first
  void index_nodes() {
    std::vector<std::pair<const aiNode*, int>> stack{{scene_.mRootNode, -1}};
    while (!stack.empty()) {
      auto [ai, parent] = stack.back();
      stack.pop_back();
      if (nodes_.size() >= static_cast<std::size_t>(kMaxLinks) * 4) {
        throw std::runtime_error("the file has more than " + std::to_string(kMaxLinks * 4) + " nodes");
      }
      Node n;
      n.ai = ai;
      n.parent = parent;
      n.depth = parent < 0 ? 0 : nodes_[parent].depth + 1;
      n.name = ai->mName.C_Str();
      if (!finite_matrix(ai->mTransformation)) {
        throw std::runtime_error("node '" + n.name + "' has a non-finite transform");
      }
      n.local_rest = to_eigen(ai->mTransformation);
      n.global_rest = parent < 0 ? n.local_rest : Matrix4(nodes_[parent].global_rest * n.local_rest);
      aiVector3D s, t;
      aiQuaternion r;
      ai->mTransformation.Decompose(s, r, t);
      n.rest_t = Vector3(t.x, t.y, t.z);
      n.rest_r = Quaternion(r.w, r.x, r.y, r.z).normalized();
      n.rest_s = Vector3(s.x, s.y, s.z);
      const int self = static_cast<int>(nodes_.size());
      nodes_.push_back(n);
      by_name_.emplace(n.name, self);  // the first node of a name, as assimp's FindNode
      for (unsigned c = ai->mNumChildren; c-- > 0;) stack.push_back({ai->mChildren[c], self});
    }
  }

  // ---- metres and Y up: A = [s C, 0; 0, 1] applied to every world matrix
  void world_axes() {
    const aiMetadata* md = scene_.mMetaData;
    const bool fbx = ext_ == ".fbx";
    if (fbx) {
      double factor = 1;  // FBX: centimetres per unit
      if (md != nullptr) {
        float f = 0;
        double d = 0;
        if (md->Get("UnitScaleFactor", f) && std::isfinite(f) && f > 0) factor = f;
        else if (md->Get("UnitScaleFactor", d) && std::isfinite(d) && d > 0) factor = d;
      }
      unit_scale_ = factor / 100.0;
      int up = 1, up_sign = 1, front = 2, front_sign = 1, coord = 0, coord_sign = 1;
      if (md != nullptr) {
        md->Get("UpAxis", up);
        md->Get("UpAxisSign", up_sign);
        md->Get("FrontAxis", front);
        md->Get("FrontAxisSign", front_sign);
        md->Get("CoordAxis", coord);
        md->Get("CoordAxisSign", coord_sign);
      }
      // rows: our x, y, z as file axes (x = coord, y = up, z = front)
      Matrix3 C = Matrix3::Zero();
      const bool valid = up >= 0 && up < 3 && front >= 0 && front < 3 && coord >= 0 && coord < 3;
      if (valid) {
        C(0, coord) = coord_sign < 0 ? -1 : 1;
        C(1, up) = up_sign < 0 ? -1 : 1;
        C(2, front) = front_sign < 0 ? -1 : 1;
      }
      if (valid && std::abs(C.determinant() - 1.0) < 1e-12) {
        axes_ = C;
      } else {
        warn("the FBX axis system (up " + std::to_string(up) + ", front " + std::to_string(front) +
             ", coord " + std::to_string(coord) + ") is not a rotation; axes kept as stored");
      }
    }
    A_.setIdentity();
    A_.topLeftCorner<3, 3>() = unit_scale_ * axes_;
  }

  // ---- bones of every skinned triangle mesh
  void collect_bones() {
    for (unsigned m = 0; m < scene_.mNumMeshes; ++m) {
      const aiMesh* mesh = scene_.mMeshes[m];
      if (mesh == nullptr || mesh->mNumBones == 0) continue;
      if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
      SourceMesh sm;
      sm.mesh = mesh;
      for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const aiBone* bone = mesh->mBones[b];
        const auto it = by_name_.find(bone->mName.C_Str());
        if (it == by_name_.end()) {
          warn("mesh '" + std::string(mesh->mName.C_Str()) + "': bone '" + bone->mName.C_Str() +
               "' has no node; its weights are dropped");
          sm.bone_node.push_back(-1);
          continue;
        }
        if (!finite_matrix(bone->mOffsetMatrix)) {
          throw std::runtime_error("bone '" + std::string(bone->mName.C_Str()) +
                                   "' has a non-finite offset matrix");
        }
        const int node = it->second;
        sm.bone_node.push_back(node);
        if (offset_.count(node) == 0) {
          offset_[node] = to_eigen(bone->mOffsetMatrix);
          offset_mesh_[node] = static_cast<int>(meshes_.size());
        }
      }
      meshes_.push_back(sm);
    }
    if (offset_.empty()) {
      throw std::runtime_error("it has no skinned mesh (no mesh with bones), so there is no "
                               "skeleton to import");
    }
  }

  // ---- the root (deepest node above every bone) and the links (nodes from it to the bones)
  void choose_links() {
    int root = offset_.begin()->first;
    for (const auto& [node, unused] : offset_) {
      (void)unused;
      int a = root, b = node;
      while (nodes_[a].depth > nodes_[b].depth) a = nodes_[a].parent;
      while (nodes_[b].depth > nodes_[a].depth) b = nodes_[b].parent;
      while (a != b) {
        a = nodes_[a].parent;
        b = nodes_[b].parent;
      }
      root = a;
    }
    root_ = root;
    is_link_.assign(nodes_.size(), 0);
    for (const auto& [node, unused] : offset_) {
      (void)unused;
      for (int n = node; n != root_ && !is_link_[n]; n = nodes_[n].parent) is_link_[n] = 1;
    }
    is_link_[root_] = 1;
    // links in depth-first node order: parents first
    for (int n = 0; n < static_cast<int>(nodes_.size()); ++n) {
      if (is_link_[n]) links_.push_back(n);
    }
    if (links_.size() > static_cast<std::size_t>(kMaxLinks)) {
      throw std::runtime_error("the skeleton has " + std::to_string(links_.size()) +
                               " bones (rule: at most " + std::to_string(kMaxLinks) + ")");
    }
    link_of_node_.assign(nodes_.size(), -1);
    for (std::size_t k = 0; k < links_.size(); ++k) link_of_node_[links_[k]] = static_cast<int>(k);
    parent_link_.assign(links_.size(), -1);
    for (std::size_t k = 1; k < links_.size(); ++k) {
      parent_link_[k] = link_of_node_[nodes_[links_[k]].parent];
    }
    // unique, non-empty link names
    std::unordered_map<std::string, int> used;
    for (int n : links_) {
      std::string name = nodes_[n].name.empty() ? "node" + std::to_string(n) : nodes_[n].name;
      std::string unique = name;
      for (int k = 2; used.count(unique) != 0; ++k) unique = name + "_" + std::to_string(k);
      used.emplace(unique, n);
      link_name_.push_back(unique);
      if (unique != nodes_[n].name) {
        warn("node '" + nodes_[n].name + "' is imported as link '" + unique + "' (names must be unique and non-empty)");
      }
    }
  }

  // ---- bind pose: the pose in which every bone's global transform times its offset matrix is
  // the same matrix B_m for all bones of mesh m (B_m maps the mesh's bind space to the file's
  // world); B_m comes from the rest pose of the mesh's top bone
  void bind_poses() {
    for (auto& sm : meshes_) {
      int top = -1;
      for (int node : sm.bone_node) {
        if (node >= 0 && (top < 0 || nodes_[node].depth < nodes_[top].depth)) top = node;
      }
      sm.B = top < 0 ? Matrix4(Matrix4::Identity())
                     : Matrix4(nodes_[top].global_rest * offset_for(sm, top));
    }
    bind_global_.assign(links_.size(), Matrix4::Identity());
    for (std::size_t k = 0; k < links_.size(); ++k) {
      const int n = links_[k];
      const auto it = offset_.find(n);
      if (it != offset_.end()) {
        const Matrix4 O = it->second;
        if (std::abs(O.topLeftCorner<3, 3>().determinant()) < 1e-12) {
          throw std::runtime_error("bone '" + nodes_[n].name + "' has a singular offset matrix");
        }
        bind_global_[k] = meshes_[offset_mesh_.at(n)].B * O.inverse();
      } else if (k == 0) {
        bind_global_[k] = nodes_[n].global_rest;
      } else {
        // a node between bones: its rest placement below its parent link's bind pose
        const int p = links_[parent_link_[k]];
        bind_global_[k] = bind_global_[parent_link_[k]] * nodes_[p].global_rest.inverse() *
                          nodes_[n].global_rest;
      }
    }
    bind_.resize(links_.size());
    double worst = 0;
    int worst_link = 0;
    for (std::size_t k = 0; k < links_.size(); ++k) {
      double e = 0;
      bind_[k] = rigid(A_ * bind_global_[k], e);
      if (e > worst) {
        worst = e;
        worst_link = static_cast<int>(k);
      }
    }
    if (worst > kScaleTolerance) {
      warn("bind pose of '" + link_name_[worst_link] + "' is scaled (largest |scale - 1| = " +
           num(worst) + " after the unit scale); links are rigid, the scale is dropped");
    }
  }

  Matrix4 offset_for(const SourceMesh& sm, int node) const;

  // ---- local transform of a node at time t of an animation (ticks)
  Matrix4 local_at(int n, const aiNodeAnim* ch, double t) const {
    const Node& node = nodes_[n];
    if (ch == nullptr) return node.local_rest;
    const auto lerp3 = [](const Vector3& a, const Vector3& b, double f) { return Vector3(a + f * (b - a)); };
    const auto slerp = [](const Quaternion& a, const Quaternion& b, double f) { return a.slerp(f, b); };
    const Vector3 T = sample_keys(ch->mPositionKeys, ch->mNumPositionKeys, t, node.rest_t, lerp3);
    const Quaternion R =
        sample_keys(ch->mRotationKeys, ch->mNumRotationKeys, t, node.rest_r, slerp).normalized();
    const Vector3 S = sample_keys(ch->mScalingKeys, ch->mNumScalingKeys, t, node.rest_s, lerp3);
    return trs(T, R, S);
  }

  struct AnimInfo {
    const aiAnimation* anim = nullptr;
    std::vector<const aiNodeAnim*> channel_of_node;  // per node, or null
    double ticks_per_second = 25;
    double start = 0, end = 0;  // ticks
    int frames = 0;
  };

  AnimInfo anim_info(const aiAnimation* a) {
    AnimInfo info;
    info.anim = a;
    info.channel_of_node.assign(nodes_.size(), nullptr);
    info.ticks_per_second = a->mTicksPerSecond;
    if (!(info.ticks_per_second > 0) || !std::isfinite(info.ticks_per_second)) {
      info.ticks_per_second = 25;
      warn("animation '" + std::string(a->mName.C_Str()) +
           "' does not say its ticks per second; 25 assumed (assimp's default)");
    }
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (unsigned c = 0; c < a->mNumChannels; ++c) {
      const aiNodeAnim* ch = a->mChannels[c];
      const auto it = by_name_.find(ch->mNodeName.C_Str());
      if (it == by_name_.end()) {
        warn("animation '" + std::string(a->mName.C_Str()) + "': channel for '" +
             ch->mNodeName.C_Str() + "' has no node; ignored");
        continue;
      }
      if (info.channel_of_node[it->second] == nullptr) info.channel_of_node[it->second] = ch;
      auto span = [&](double first, double last) {
        if (!std::isfinite(first) || !std::isfinite(last)) {
          throw std::runtime_error("animation '" + std::string(a->mName.C_Str()) +
                                   "' has a non-finite key time");
        }
        lo = std::min(lo, first);
        hi = std::max(hi, last);
      };
      // keys must be sorted for the binary search; assimp's importers sort them
      auto check_sorted = [&](const auto* keys, unsigned n) {
        for (unsigned k = 1; k < n; ++k) {
          if (keys[k].mTime < keys[k - 1].mTime) {
            throw std::runtime_error("animation '" + std::string(a->mName.C_Str()) + "', node '" +
                                     ch->mNodeName.C_Str() + "': key times decrease");
          }
        }
        if (n > 0) span(keys[0].mTime, keys[n - 1].mTime);
      };
      check_sorted(ch->mPositionKeys, ch->mNumPositionKeys);
      check_sorted(ch->mRotationKeys, ch->mNumRotationKeys);
      check_sorted(ch->mScalingKeys, ch->mNumScalingKeys);
    }
    if (!(hi >= lo)) lo = hi = 0;
    info.start = lo;
    info.end = hi;
    const double seconds = (hi - lo) / info.ticks_per_second;
    // key times are often single precision (glTF): a last key within a thousandth of a frame
    // past a frame time does not get a frame of its own
    const double n = std::ceil(seconds * options_.frame_rate - 1e-3) + 1;
    if (!(n <= kMaxFrames)) {
      throw std::runtime_error("animation '" + std::string(a->mName.C_Str()) + "' lasts " +
                               num(seconds) + " s: more than " + num(kMaxFrames) + " frames");
    }
    info.frames = static_cast<int>(n);
    return info;
  }

  double tick_of_frame(const AnimInfo& info, int k) const {
    return std::min(info.end, info.start + k / options_.frame_rate * info.ticks_per_second);
  }

  // rigid world poses of the links at time t (ticks); worst scale deviation into `scale_error`
  void link_poses(const AnimInfo& info, double t, std::vector<Transform>& out, double& scale_error) {
    // the root's global transform: its ancestors may be animated too
    std::vector<int> chain;
    for (int n = root_; n >= 0; n = nodes_[n].parent) chain.push_back(n);
    Matrix4 G = Matrix4::Identity();
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) G = G * local_at(*it, info.channel_of_node[*it], t);
    global_.resize(links_.size());
    global_[0] = G;
    for (std::size_t k = 1; k < links_.size(); ++k) {
      // nodes between a link and its parent link do not exist: links are contiguous paths
      const int n = links_[k];
      global_[k] = global_[parent_link_[k]] * local_at(n, info.channel_of_node[n], t);
    }
    out.resize(links_.size());
    for (std::size_t k = 0; k < links_.size(); ++k) {
      double e = 0;
      out[k] = rigid(A_ * global_[k], e);
      scale_error = std::max(scale_error, e);
    }
  }

  // ---- offsets of non-root bones over every clip: which translate, how far spherical ones drift
  void sample_offsets() {
    const std::size_t nl = links_.size();
    is_free_.assign(nl, 0);
    is_free_[0] = 1;
    dropped_.assign(nl, 0.0);
    std::vector<Vector3> lo(nl, Vector3::Constant(std::numeric_limits<double>::infinity()));
    std::vector<Vector3> hi(nl, Vector3::Constant(-std::numeric_limits<double>::infinity()));
    double scale_error = 0;
    std::vector<Transform> X;
    for (unsigned a = 0; a < scene_.mNumAnimations; ++a) {
      anims_.push_back(anim_info(scene_.mAnimations[a]));
      const AnimInfo& info = anims_.back();
      for (int k = 0; k < info.frames; ++k) {
        link_poses(info, tick_of_frame(info, k), X, scale_error);
        for (std::size_t j = 1; j < nl; ++j) {
          const Vector3 p_rel = X[parent_link_[j]].inverse_apply(X[j].p);
          lo[j] = lo[j].cwiseMin(p_rel);
          hi[j] = hi[j].cwiseMax(p_rel);
          const Vector3 bind_rel = bind_[parent_link_[j]].inverse_apply(bind_[j].p);
          dropped_[j] = std::max(dropped_[j], (p_rel - bind_rel).norm());
        }
      }
    }
    for (std::size_t j = 1; j < nl; ++j) {
      if (lo[j].x() > hi[j].x()) continue;  // no frames
      const double moves = (hi[j] - lo[j]).norm();
      if (moves > options_.translating_tolerance) {
        is_free_[j] = 1;
        warn("bone '" + link_name_[j] + "' moves by up to " + num(moves) +
             " m from its parent during a clip; it gets a free joint");
        dropped_[j] = 0;
      } else if (dropped_[j] > 1e-6) {
        warn("bone '" + link_name_[j] + "': the clips place it up to " + num(dropped_[j]) +
             " m from its bind offset; a spherical joint keeps the bind offset");
      }
    }
    if (scale_error > kScaleTolerance) {
      warn("the clips scale bones (largest |scale - 1| = " + num(scale_error) +
           " after the unit scale); links are rigid, the scale is dropped");
    }
  }

  // ---- the model: joints from the bind pose, masses from bone lengths
  void build_model() {
    const std::size_t nl = links_.size();
    // bone length: to the children (links, else end nodes such as Blender's "_end"), else half
    // the parent's
    std::vector<Vector3> toward(nl, Vector3::Zero());  // mean child offset, link frame
    std::vector<double> length(nl, 0);
    for (std::size_t k = 0; k < nl; ++k) {
      std::vector<Vector3> ends;
      for (std::size_t c = k + 1; c < nl; ++c) {
        if (parent_link_[c] == static_cast<int>(k)) ends.push_back(bind_[k].inverse_apply(bind_[c].p));
      }
      if (ends.empty()) {
        const Node& node = nodes_[links_[k]];
        for (unsigned c = 0; c < node.ai->mNumChildren; ++c) {
          const aiNode* child = node.ai->mChildren[c];
          if (child->mNumMeshes > 0) continue;
          const Matrix4 G = A_ * bind_global_[k] * to_eigen(child->mTransformation);
          ends.push_back(bind_[k].inverse_apply(G.topRightCorner<3, 1>()));
        }
      }
      for (const Vector3& e : ends) {
        toward[k] += e / static_cast<double>(ends.size());
        length[k] += e.norm() / static_cast<double>(ends.size());
      }
    }
    double extent = 0;
    for (std::size_t k = 0; k < nl; ++k) extent = std::max(extent, (bind_[k].p - bind_[0].p).norm());
    const double min_length = std::max(1e-3 * extent, 1e-4);
    for (std::size_t k = 0; k < nl; ++k) {
      if (length[k] < min_length && k > 0) {
        length[k] = 0.5 * length[parent_link_[k]];
        // continue the parent's direction
        toward[k] = bind_[k].R.transpose() * (bind_[k].p - bind_[parent_link_[k]].p);
        if (toward[k].norm() > 0) toward[k] = toward[k].normalized() * length[k];
      }
      length[k] = std::max(length[k], min_length);
    }
    double total_length = 0;
    for (double l : length) total_length += l;

    ModelBuilder b(stem_);
    for (std::size_t k = 0; k < nl; ++k) {
      LinkSpec l;
      l.name = link_name_[k];
      l.parent = k == 0 ? "" : link_name_[parent_link_[k]];
      l.joint.type = is_free_[k] ? JointType::kFree : JointType::kSpherical;
      l.joint.X_PJ = k == 0 ? bind_[0] : bind_[parent_link_[k]].inverse() * bind_[k];
      // the builder wants an orthonormal rotation to 1e-6; re-orthonormalize the product
      l.joint.X_PJ.R = Quaternion(l.joint.X_PJ.R).normalized().toRotationMatrix();
      // a slender solid cylinder along the bone, radius a tenth of its length
      const double m = options_.total_mass * length[k] / total_length;
      const double r = 0.1 * length[k];
      const Vector3 axis = toward[k].norm() > 0 ? Vector3(toward[k].normalized()) : Vector3::UnitY();
      l.mass = m;
      l.com = toward[k].norm() > 0 ? Vector3(0.5 * toward[k]) : Vector3::Zero();
      const Matrix3 aa = axis * axis.transpose();
      l.I_com = m * (3 * r * r + length[k] * length[k]) / 12.0 * (Matrix3::Identity() - aa) +
                0.5 * m * r * r * aa;
      b.add_link(std::move(l));
    }
    model_ = b.finalize();
    model_link_.resize(nl);
    for (std::size_t k = 0; k < nl; ++k) model_link_[k] = model_->link_index(link_name_[k]);
  }

  // ---- the skinned mesh, in the bind pose, in our world
  void build_mesh() {
    std::vector<int> bone_of_link(links_.size(), -1);
    auto bone = [&](int link) {
      if (bone_of_link[link] < 0) {
        bone_of_link[link] = static_cast<int>(mesh_.bones.size());
        mesh_.bones.push_back(model_link_[link]);
        mesh_.inverse_bind.push_back(bind_[link].inverse());
      }
      return bone_of_link[link];
    };
    std::size_t unweighted = 0;
    bool colored = false;
    for (const SourceMesh& sm : meshes_) {
      const aiMesh* mesh = sm.mesh;
      const Matrix4 M = A_ * sm.B;
      const Matrix3 N = M.topLeftCorner<3, 3>().inverse().transpose();
      const std::size_t base = mesh_.positions.size();
      const std::size_t nv = mesh->mNumVertices;
      if (base + nv > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
        throw std::runtime_error("too many vertices");
      }
      if (mesh_.name.empty()) mesh_.name = mesh->mName.C_Str();
      for (std::size_t v = 0; v < nv; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const Eigen::Vector4d pw = M * Eigen::Vector4d(p.x, p.y, p.z, 1);
        mesh_.positions.push_back(pw.head<3>().cast<float>());
        if (mesh->mNormals != nullptr) {
          const aiVector3D& n = mesh->mNormals[v];
          Vector3 nw = N * Vector3(n.x, n.y, n.z);
          if (nw.norm() > 0) nw.normalize();
          mesh_.normals.push_back(nw.cast<float>());
        } else {
          mesh_.normals.emplace_back(0.0f, 0.0f, 0.0f);  // the exporter computes face normals
        }
      }
      // up to four influences per vertex, the largest kept
      std::vector<std::vector<std::pair<float, int>>> infl(nv);
      for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const int node = sm.bone_node[b];
        if (node < 0) continue;
        const int link = link_of_node_[node];
        const aiBone* ab = mesh->mBones[b];
        for (unsigned k = 0; k < ab->mNumWeights; ++k) {
          const aiVertexWeight& vw = ab->mWeights[k];
          if (vw.mVertexId >= nv || !(vw.mWeight > 0) || !std::isfinite(vw.mWeight)) continue;
          infl[vw.mVertexId].push_back({vw.mWeight, bone(link)});
        }
      }
      for (std::size_t v = 0; v < nv; ++v) {
        auto& iv = infl[v];
        std::sort(iv.begin(), iv.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
        std::array<int, 4> j{0, 0, 0, 0};
        std::array<float, 4> w{0, 0, 0, 0};
        if (iv.empty()) {
          ++unweighted;
          j[0] = bone(0);
          w[0] = 1;
        }
        float sum = 0;
        for (std::size_t k = 0; k < iv.size() && k < 4; ++k) sum += iv[k].first;
        for (std::size_t k = 0; k < iv.size() && k < 4; ++k) {
          j[k] = iv[k].second;
          w[k] = iv[k].first / sum;
        }
        mesh_.joints.push_back(j);
        mesh_.weights.push_back(w);
      }
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3) continue;
        std::array<int, 3> t{};
        bool ok = true;
        for (int c = 0; c < 3; ++c) {
          ok = ok && face.mIndices[c] < nv;
          t[c] = static_cast<int>(base + (ok ? face.mIndices[c] : 0));
        }
        if (ok) mesh_.triangles.push_back(t);
      }
      if (!colored && mesh->mMaterialIndex < scene_.mNumMaterials) {
        const aiMaterial* mat = scene_.mMaterials[mesh->mMaterialIndex];
        aiColor4D c;
        if (mat->Get(AI_MATKEY_BASE_COLOR, c) == aiReturn_SUCCESS ||
            mat->Get(AI_MATKEY_COLOR_DIFFUSE, c) == aiReturn_SUCCESS) {
          const Eigen::Vector4f col(c.r, c.g, c.b, c.a);
          if (col.allFinite()) mesh_.base_color = col.cwiseMax(0.0f).cwiseMin(1.0f);
          colored = true;
        }
      }
    }
    if (unweighted > 0) {
      warn(std::to_string(unweighted) + " vertices have no bone weights; they follow the root '" +
           link_name_[0] + "'");
    }
  }

  // ---- clips: each animation resampled at the frame rate
  void build_clips() {
    const Model& m = *model_;
    std::vector<Transform> X;
    double scale_error = 0;
    for (const AnimInfo& info : anims_) {
      ImportedClip c;
      c.name = info.anim->mName.C_Str();
      c.start_time = info.start / info.ticks_per_second;
      c.clip.frame_time = 1.0 / options_.frame_rate;
      for (int k = 0; k < info.frames; ++k) {
        link_poses(info, tick_of_frame(info, k), X, scale_error);
        Eigen::VectorXd q = neutral_configuration(m);
        for (std::size_t j = 0; j < links_.size(); ++j) {
          const int i = model_link_[j];
          const int iq = m.idx_q[i];
          const Transform& P = m.X_PJ[i];
          // the joint's motion: X_PJ⁻¹ · (pose relative to the parent link)
          const Transform rel = j == 0 ? X[0] : X[parent_link_[j]].inverse() * X[j];
          const Quaternion r = Quaternion(P.R.transpose() * rel.R).normalized();
          if (m.joint_type[i] == JointType::kFree) {
            q.segment<3>(iq) = P.R.transpose() * (rel.p - P.p);
            set_quaternion_at(q, iq + 3, r);
          } else {
            set_quaternion_at(q, iq, r);
          }
        }
        c.clip.frames.push_back(std::move(q));
      }
      clips_.push_back(std::move(c));
    }
  }

  void write(ReplyWriter& w) {
    w.str(write_character_json(*model_));
    // mesh
    w.str(mesh_.name);
    w.u32(static_cast<std::uint32_t>(mesh_.positions.size()));
    for (std::size_t v = 0; v < mesh_.positions.size(); ++v) {
      for (int c = 0; c < 3; ++c) w.f32(mesh_.positions[v][c]);
      for (int c = 0; c < 3; ++c) w.f32(mesh_.normals[v][c]);
      for (int c = 0; c < 4; ++c) w.i32(mesh_.joints[v][c]);
      for (int c = 0; c < 4; ++c) w.f32(mesh_.weights[v][c]);
    }
    w.u32(static_cast<std::uint32_t>(mesh_.triangles.size()));
    for (const auto& t : mesh_.triangles) for (int c : t) w.i32(c);
    w.u32(static_cast<std::uint32_t>(mesh_.bones.size()));
    for (std::size_t b = 0; b < mesh_.bones.size(); ++b) {
      w.i32(mesh_.bones[b]);
      const Transform& X = mesh_.inverse_bind[b];
      for (int r = 0; r < 3; ++r) for (int c = 0; c < 3; ++c) w.f64(X.R(r, c));
      for (int r = 0; r < 3; ++r) w.f64(X.p[r]);
    }
    for (int c = 0; c < 4; ++c) w.f32(mesh_.base_color[c]);
    // clips
    w.u32(static_cast<std::uint32_t>(clips_.size()));
    for (const ImportedClip& c : clips_) {
      w.str(c.name);
      w.f64(c.start_time);
      w.f64(c.clip.frame_time);
      w.u32(static_cast<std::uint32_t>(c.clip.frames.size()));
      for (const auto& q : c.clip.frames) w.raw(q.data(), sizeof(double) * q.size());
    }
    // scale, dropped offsets per model link, warnings
    w.f64(unit_scale_);
    std::vector<double> dropped(model_->njoints, 0.0);
    for (std::size_t k = 0; k < links_.size(); ++k) dropped[model_link_[k]] = dropped_[k];
    w.u32(static_cast<std::uint32_t>(dropped.size()));
    for (double d : dropped) w.f64(d);
    w.u32(static_cast<std::uint32_t>(warnings_.size()));
    for (const auto& s : warnings_) w.str(s);
  }

  void warn(const std::string& what) { warnings_.push_back(source_ + ": " + what); }
  static std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return buf;
  }

  const aiScene& scene_;
  std::string source_, ext_, stem_;
  ImportOptions options_;
  std::vector<Node> nodes_;
  std::unordered_map<std::string, int> by_name_;
  double unit_scale_ = 1;
  Matrix3 axes_ = Matrix3::Identity();
  Matrix4 A_ = Matrix4::Identity();
  std::vector<SourceMesh> meshes_;
  std::map<int, Matrix4> offset_;       // bone node → offset matrix (first mesh naming it)
  std::map<int, int> offset_mesh_;      // bone node → that mesh
  int root_ = 0;
  std::vector<char> is_link_;
  std::vector<int> links_;         // node of each link, parents first
  std::vector<int> link_of_node_;  // per node, or -1
  std::vector<int> parent_link_;   // per link, -1 for the root
  std::vector<std::string> link_name_;
  std::vector<Matrix4> bind_global_;  // file world, per link
  std::vector<Transform> bind_;       // our world, rigid, per link
  std::vector<Matrix4> global_;       // scratch: file world per link at one time
  std::vector<AnimInfo> anims_;
  std::vector<char> is_free_;
  std::vector<double> dropped_;
  std::shared_ptr<const Model> model_;
  std::vector<int> model_link_;  // model link index of each link
  SkinnedMesh mesh_;
  std::vector<ImportedClip> clips_;
  std::vector<std::string> warnings_;
};

Matrix4 Converter::offset_for(const SourceMesh& sm, int node) const {
  for (unsigned b = 0; b < sm.mesh->mNumBones; ++b) {
    if (sm.bone_node[b] == node) return to_eigen(sm.mesh->mBones[b]->mOffsetMatrix);
  }
  return Matrix4::Identity();
}

// the child's work: import with assimp, convert, write the reply
int import_in_child(const std::string& path, const ImportOptions& options, int fd) {
  ReplyWriter w;
  w.raw(kReplyMagic, sizeof kReplyMagic);
  std::string error;
  std::string body;
  try {
    Assimp::Importer importer;
    importer.SetIOHandler(new FolderIOSystem(fs::weakly_canonical(fs::path(path)).parent_path()));
    importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);
    importer.SetPropertyInteger(AI_CONFIG_PP_LBW_MAX_WEIGHTS, 4);
    const unsigned flags = aiProcess_Triangulate | aiProcess_LimitBoneWeights |
                           aiProcess_SortByPType | aiProcess_ValidateDataStructure;
    const aiScene* scene = importer.ReadFile(path, flags);
    if (scene == nullptr || scene->mRootNode == nullptr) {
      const std::string why = importer.GetErrorString();
      // assimp catches the allocation failure itself: it is the memory limit
      if (why.find("bad_alloc") != std::string::npos) throw std::bad_alloc();
      error = "assimp could not read it: " + why;
    } else {
      ReplyWriter body_writer;
      Converter(*scene, path, options).run(body_writer);
      body = std::move(body_writer.bytes());
    }
  } catch (const std::bad_alloc&) {
    throw;  // the sandbox reports it as the memory limit
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (error.empty()) {
    w.u8(kReplyOk);
    w.raw(body.data(), body.size());
  } else {
    w.u8(kReplyError);
    w.str(error);
  }
  return write_all(fd, w.bytes().data(), w.bytes().size()) ? 0 : 1;
}

// ---------------------------------------------------------------------------------------------
// in the parent: checks before the child starts, and the reply

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ModelError({path + ": " + what});
}

// the extension names the format; the first bytes must agree
void check_format(const std::string& path, const std::string& ext, const std::string& head) {
  const bool has_nul = head.find('\0') != std::string::npos;
  std::size_t start = 0;
  if (head.compare(0, 3, "\xEF\xBB\xBF") == 0) start = 3;
  while (start < head.size() && std::isspace(static_cast<unsigned char>(head[start]))) ++start;
  const char first = start < head.size() ? head[start] : '\0';
  if (ext == ".glb") {
    if (head.compare(0, 4, "glTF") != 0) fail(path, "not a GLB file (it does not start with 'glTF')");
  } else if (ext == ".gltf") {
    if (has_nul || first != '{') fail(path, "not a glTF JSON file (it does not start with '{')");
  } else if (ext == ".fbx") {
    const bool binary = head.compare(0, 18, "Kaydara FBX Binary") == 0;
    const bool ascii = !has_nul && (first == ';' || head.find("FBXHeaderExtension") != std::string::npos);
    if (!binary && !ascii) {
      fail(path, "not an FBX file (neither the 'Kaydara FBX Binary' signature nor an ASCII FBX header)");
    }
  } else if (ext == ".dae") {
    if (has_nul || first != '<' || head.find("COLLADA") == std::string::npos) {
      fail(path, "not a COLLADA file (no XML document with a COLLADA element at its start)");
    }
  } else {
    fail(path, "unsupported extension '" + ext + "' (rule: .gltf, .glb, .fbx or .dae)");
  }
}

constexpr std::size_t kMaxReplyString = std::size_t{64} << 20;

SkinnedImport decode_reply(const std::string& path, const std::string& reply) {
  ReplyReader r(reply);
  r.expect_magic();
  const std::uint8_t status = r.u8();
  if (status == kReplyError) fail(path, r.str(1 << 16));
  if (status != kReplyOk) throw std::runtime_error("an unknown status byte");

  SkinnedImport out;
  const LoadResult loaded = load_character_json_string(r.str(kMaxReplyString), path, "");
  out.model = loaded.model;
  const Model& m = *out.model;
  SkinnedMesh& s = out.mesh;
  s.name = r.str(1 << 16);
  const std::size_t nv = r.count(4 * 14);
  s.positions.resize(nv);
  s.normals.resize(nv);
  s.joints.resize(nv);
  s.weights.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    for (int c = 0; c < 3; ++c) s.positions[v][c] = r.f32();
    for (int c = 0; c < 3; ++c) s.normals[v][c] = r.f32();
    for (int c = 0; c < 4; ++c) s.joints[v][c] = r.i32();
    for (int c = 0; c < 4; ++c) s.weights[v][c] = r.f32();
  }
  const std::size_t nt = r.count(12);
  s.triangles.resize(nt);
  for (auto& t : s.triangles) {
    for (int& c : t) {
      c = r.i32();
      if (c < 0 || static_cast<std::size_t>(c) >= nv) throw std::runtime_error("a triangle index out of range");
    }
  }
  const std::size_t nb = r.count(4 + 12 * 8);
  std::vector<char> bound(m.njoints, 0);
  for (std::size_t b = 0; b < nb; ++b) {
    const int link = r.i32();
    if (link < 1 || link >= m.njoints || bound[link]++) throw std::runtime_error("a bone that is not a link");
    Transform X;
    for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) X.R(i, j) = r.f64();
    for (int i = 0; i < 3; ++i) X.p[i] = r.f64();
    if (!X.R.allFinite() || !X.p.allFinite() ||
        (X.R.transpose() * X.R - Matrix3::Identity()).norm() > 1e-6) {
      throw std::runtime_error("an inverse bind matrix that is not rigid");
    }
    s.bones.push_back(link);
    s.inverse_bind.push_back(X);
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (!s.positions[v].allFinite() || !s.normals[v].allFinite()) throw std::runtime_error("a non-finite vertex");
    float sum = 0;
    for (int c = 0; c < 4; ++c) {
      const float w = s.weights[v][c];
      if (!std::isfinite(w) || w < 0) throw std::runtime_error("a negative or non-finite weight");
      if (w > 0 && (s.joints[v][c] < 0 || static_cast<std::size_t>(s.joints[v][c]) >= nb)) {
        throw std::runtime_error("a vertex joint that is not a bone");
      }
      sum += w;
    }
    if (!(std::abs(sum - 1.0f) < 1e-3f)) throw std::runtime_error("vertex weights that do not sum to 1");
  }
  for (int c = 0; c < 4; ++c) s.base_color[c] = r.f32();
  if (!s.base_color.allFinite()) throw std::runtime_error("a non-finite colour");

  const std::size_t nc = r.count(4 + 8 + 8 + 4);
  for (std::size_t k = 0; k < nc; ++k) {
    ImportedClip c;
    c.name = r.str(1 << 16);
    c.start_time = r.f64();
    c.clip.frame_time = r.f64();
    const std::size_t nf = r.count(sizeof(double) * static_cast<std::size_t>(std::max(1, m.nq)));
    c.clip.frames.resize(nf, Eigen::VectorXd(m.nq));
    for (auto& q : c.clip.frames) for (int i = 0; i < m.nq; ++i) q[i] = r.f64();
    const std::string e = check_clip(m, c.clip);
    if (!std::isfinite(c.start_time) || !e.empty()) throw std::runtime_error("a bad clip: " + e);
    out.clips.push_back(std::move(c));
  }
  out.unit_scale = r.f64();
  if (!(out.unit_scale > 0) || !std::isfinite(out.unit_scale)) throw std::runtime_error("a bad unit scale");
  const std::size_t nd = r.count(8);
  if (nd != static_cast<std::size_t>(m.njoints)) throw std::runtime_error("offsets for another model");
  out.dropped_offset.resize(nd);
  for (double& d : out.dropped_offset) {
    d = r.f64();
    if (!std::isfinite(d) || d < 0) throw std::runtime_error("a bad offset");
  }
  const std::size_t nw = r.count(4);
  for (std::size_t k = 0; k < nw; ++k) out.warnings.push_back(r.str(1 << 16));
  for (const auto& w : loaded.warnings) out.warnings.push_back(w);
  if (!r.at_end()) throw std::runtime_error("bytes after its end");
  return out;
}

}  // namespace

SkinnedImport import_skinned_file(const std::string& path,
                                  const ImportLimits& limits,
                                  const ImportOptions& options) {
  if (!(options.frame_rate > 0 && options.frame_rate <= 1000)) {
    fail(path, "frame rate " + std::to_string(options.frame_rate) + " is outside (0, 1000]");
  }
  if (!(options.total_mass > 0 && std::isfinite(options.total_mass))) {
    fail(path, "total mass must be a finite number > 0");
  }
  // before any process starts: the file exists, is regular, not empty, not too large, and its
  // first bytes agree with its extension
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) fail(path, std::string("cannot open it: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) fail(path, "not a regular file");
  if (st.st_size == 0) fail(path, "the file is empty");
  if (static_cast<std::uint64_t>(st.st_size) > limits.max_file_bytes) {
    fail(path, std::to_string(st.st_size) + " bytes is more than the import limit of " +
                   std::to_string(limits.max_file_bytes) + " bytes");
  }
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::string head(kSniffBytes, '\0');
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot open it: ") + std::strerror(errno));
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
  }
  check_format(path, ext, head);

  SandboxLimits sl;
  sl.memory_bytes = limits.memory_bytes;
  sl.cpu_seconds = limits.cpu_seconds;
  sl.timeout_seconds = limits.timeout_seconds;
  sl.max_reply_bytes = limits.max_reply_bytes;
  const SandboxResult r =
      run_sandboxed([&](int fd) { return import_in_child(path, options, fd); }, sl);
  if (r.status != SandboxStatus::kOk) fail(path, "the import process " + r.message);
  try {
    return decode_reply(path, r.reply);
  } catch (const ModelError&) {
    throw;
  } catch (const std::exception& e) {
    fail(path, std::string("the import process sent a malformed reply: ") + e.what());
  }
}

}  // namespace io
