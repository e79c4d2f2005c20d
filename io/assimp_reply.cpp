#include "io/assimp_reply.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "io/character_json.hpp"

namespace io::assimp_detail {

namespace {

// the reply's first bytes: format and version of the child → parent wire format
constexpr char kReplyMagic[8] = {'P', 'D', 'S', 'K', 'I', 'N', '0', '2'};
constexpr std::uint8_t kReplyOk = 0;
constexpr std::uint8_t kReplyError = 1;
// longest model JSON, and longest name, message or warning, the parent accepts
constexpr std::size_t kMaxReplyString = std::size_t{64} << 20;
constexpr std::size_t kMaxReplyName = std::size_t{1} << 16;

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
    if (in_.size() - at_ < n) {
      throw std::runtime_error("it ends early, at byte " + std::to_string(at_));
    }
  }
  const std::string& in_;
  std::size_t at_ = 0;
};

// ---------------------------------------------------------------------------------------------
// in the child

void write_mesh(const SkinnedMesh& mesh, ReplyWriter& w) {
  w.str(mesh.name);
  w.u32(static_cast<std::uint32_t>(mesh.positions.size()));
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int c = 0; c < 3; ++c) w.f32(mesh.positions[v][c]);
    for (int c = 0; c < 3; ++c) w.f32(mesh.normals[v][c]);
    for (int c = 0; c < 4; ++c) w.i32(mesh.joints[v][c]);
    for (int c = 0; c < 4; ++c) w.f32(mesh.weights[v][c]);
  }
  w.u32(static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    for (int c : t) w.i32(c);
  }
  w.u32(static_cast<std::uint32_t>(mesh.bones.size()));
  for (std::size_t b = 0; b < mesh.bones.size(); ++b) {
    w.i32(mesh.bones[b]);
    const Transform& X = mesh.inverse_bind[b];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) w.f64(X.R(r, c));
    }
    for (int r = 0; r < 3; ++r) w.f64(X.p[r]);
  }
  for (int c = 0; c < 4; ++c) w.f32(mesh.base_color[c]);
  w.u32(static_cast<std::uint32_t>(mesh.uvs.size()));
  for (const auto& uv : mesh.uvs) w.raw(uv.data(), 2 * sizeof(float));
  w.u32(static_cast<std::uint32_t>(mesh.parts.size()));
  for (const core::MeshPart& p : mesh.parts) {
    w.i32(p.first_triangle);
    w.i32(p.triangle_count);
    for (int c = 0; c < 4; ++c) w.f32(p.base_color[c]);
    w.i32(p.texture);
  }
  w.u32(static_cast<std::uint32_t>(mesh.textures.size()));
  for (const core::MeshTexture& t : mesh.textures) {
    w.str(t.mime_type);
    w.str(t.bytes);
  }
}

// ---------------------------------------------------------------------------------------------
// in the parent

// bones as link indices (each bound once) with rigid inverse bind poses
void read_bones(ReplyReader& r, const Model& m, SkinnedMesh& s) {
  const std::size_t nb = r.count(4 + 12 * 8);
  std::vector<char> bound(m.njoints, 0);
  for (std::size_t b = 0; b < nb; ++b) {
    const int link = r.i32();
    if (link < 1 || link >= m.njoints || bound[link]++) {
      throw std::runtime_error("a bone that is not a link");
    }
    Transform X;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) X.R(i, j) = r.f64();
    }
    for (int i = 0; i < 3; ++i) X.p[i] = r.f64();
    if (!X.R.allFinite() || !X.p.allFinite() ||
        (X.R.transpose() * X.R - Matrix3::Identity()).norm() > 1e-6) {
      throw std::runtime_error("an inverse bind matrix that is not rigid");
    }
    s.bones.push_back(link);
    s.inverse_bind.push_back(X);
  }
}

// finite vertices whose non-negative weights sum to 1 on bones of the mesh
void check_vertices(const SkinnedMesh& s) {
  const std::size_t nb = s.bones.size();
  for (std::size_t v = 0; v < s.positions.size(); ++v) {
    if (!s.positions[v].allFinite() || !s.normals[v].allFinite()) {
      throw std::runtime_error("a non-finite vertex");
    }
    float sum = 0;
    for (int c = 0; c < 4; ++c) {
      const float w = s.weights[v][c];
      if (!std::isfinite(w) || w < 0) throw std::runtime_error("a negative or non-finite weight");
      if (w > 0 && (s.joints[v][c] < 0 || static_cast<std::size_t>(s.joints[v][c]) >= nb)) {
        throw std::runtime_error("a vertex joint that is not a bone");
      }
      sum += w;
    }
    if (!(std::abs(sum - 1.0f) < 1e-3f)) {
      throw std::runtime_error("vertex weights that do not sum to 1");
    }
  }
}

// the mesh in the order write_mesh wrote it, each index checked against what it refers to
void read_mesh(ReplyReader& r, const Model& m, SkinnedMesh& s) {
  s.name = r.str(kMaxReplyName);
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
      if (c < 0 || static_cast<std::size_t>(c) >= nv) {
        throw std::runtime_error("a triangle index out of range");
      }
    }
  }
  read_bones(r, m, s);
  check_vertices(s);
  for (int c = 0; c < 4; ++c) s.base_color[c] = r.f32();
  if (!s.base_color.allFinite()) throw std::runtime_error("a non-finite colour");
  s.uvs.resize(r.count(2 * sizeof(float)));
  for (auto& uv : s.uvs) {
    uv.x() = r.f32();  // one statement each: the order of a call's arguments is unspecified
    uv.y() = r.f32();
  }
  s.parts.resize(r.count(4 * 7));
  for (core::MeshPart& p : s.parts) {
    p.first_triangle = r.i32();
    p.triangle_count = r.i32();
    for (int c = 0; c < 4; ++c) p.base_color[c] = r.f32();
    p.texture = r.i32();
  }
  s.textures.resize(r.count(8));
  for (core::MeshTexture& t : s.textures) {
    t.mime_type = r.str(kMaxReplyName);
    t.bytes = r.str(kMaxReplyString);
  }
  const std::string e = core::check_mesh_materials(s);
  if (!e.empty()) throw std::runtime_error("a bad mesh: " + e);
}

void read_clips(ReplyReader& r, const Model& m, std::vector<ImportedClip>& clips) {
  const std::size_t nc = r.count(4 + 8 + 8 + 4);
  for (std::size_t k = 0; k < nc; ++k) {
    ImportedClip c;
    c.name = r.str(kMaxReplyName);
    c.start_time = r.f64();
    c.clip.frame_time = r.f64();
    const std::size_t nf = r.count(sizeof(double) * static_cast<std::size_t>(std::max(1, m.nq)));
    c.clip.frames.resize(nf, Eigen::VectorXd(m.nq));
    for (auto& q : c.clip.frames) {
      for (int i = 0; i < m.nq; ++i) q[i] = r.f64();
    }
    const std::string e = core::check_clip(m, c.clip);
    if (!std::isfinite(c.start_time) || !e.empty()) throw std::runtime_error("a bad clip: " + e);
    clips.push_back(std::move(c));
  }
}

// unit scale, dropped offsets (one per link of the model) and the child's warnings
void read_tail(ReplyReader& r, const Model& m, SkinnedImport& out) {
  out.unit_scale = r.f64();
  if (!(out.unit_scale > 0) || !std::isfinite(out.unit_scale)) {
    throw std::runtime_error("a bad unit scale");
  }
  const std::size_t nd = r.count(8);
  if (nd != static_cast<std::size_t>(m.njoints)) {
    throw std::runtime_error("offsets for another model");
  }
  out.dropped_offset.resize(nd);
  for (double& d : out.dropped_offset) {
    d = r.f64();
    if (!std::isfinite(d) || d < 0) throw std::runtime_error("a bad offset");
  }
  const std::size_t nw = r.count(4);
  for (std::size_t k = 0; k < nw; ++k) out.warnings.push_back(r.str(kMaxReplyName));
}

}  // namespace

std::string encode_reply(const SkinnedImport& result) {
  ReplyWriter w;
  w.raw(kReplyMagic, sizeof kReplyMagic);
  w.u8(kReplyOk);
  w.str(write_character_json(*result.model));
  write_mesh(result.mesh, w);
  w.u32(static_cast<std::uint32_t>(result.clips.size()));
  for (const ImportedClip& c : result.clips) {
    w.str(c.name);
    w.f64(c.start_time);
    w.f64(c.clip.frame_time);
    w.u32(static_cast<std::uint32_t>(c.clip.frames.size()));
    for (const auto& q : c.clip.frames) w.raw(q.data(), sizeof(double) * q.size());
  }
  w.f64(result.unit_scale);
  w.u32(static_cast<std::uint32_t>(result.dropped_offset.size()));
  for (double d : result.dropped_offset) w.f64(d);
  w.u32(static_cast<std::uint32_t>(result.warnings.size()));
  for (const auto& s : result.warnings) w.str(s);
  return std::move(w.bytes());
}

std::string encode_error_reply(const std::string& message) {
  ReplyWriter w;
  w.raw(kReplyMagic, sizeof kReplyMagic);
  w.u8(kReplyError);
  w.str(message);
  return std::move(w.bytes());
}

SkinnedImport decode_reply(const std::string& path, const std::string& reply) {
  ReplyReader r(reply);
  r.expect_magic();
  const std::uint8_t status = r.u8();
  if (status == kReplyError) throw ModelError({path + ": " + r.str(kMaxReplyName)});
  if (status != kReplyOk) throw std::runtime_error("an unknown status byte");

  SkinnedImport out;
  const LoadResult loaded = load_character_json_string(r.str(kMaxReplyString), path, "");
  out.model = loaded.model;
  const Model& m = *out.model;
  read_mesh(r, m, out.mesh);
  read_clips(r, m, out.clips);
  read_tail(r, m, out);
  for (const auto& w : loaded.warnings) out.warnings.push_back(w);
  if (!r.at_end()) throw std::runtime_error("bytes after its end");
  return out;
}

}  // namespace io::assimp_detail
