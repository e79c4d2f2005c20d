#include "io/gltf_mesh.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace io::gltf_detail {

namespace {

// a rotation that far from orthonormal is not a placement or a bind pose
constexpr double kRotationTolerance = 1e-6;

}  // namespace

bool is_rotation(const Matrix3& R) {
  return R.allFinite() && (R.transpose() * R - Matrix3::Identity()).norm() < kRotationTolerance &&
         R.determinant() > 0;
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
    if (seen[link]++)
      fail("bone " + std::to_string(b) + ": link '" + model.link_name[link] + "' is bound twice");
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
      if (w > 0 &&
          (skin.joints[v][k] < 0 || static_cast<size_t>(skin.joints[v][k]) >= skin.bones.size())) {
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
  const std::string materials = core::check_mesh_materials(skin);
  if (!materials.empty()) fail(materials);
}

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

void normalized_influences(const std::array<int, 4>& joints,
                           const std::array<float, 4>& weights,
                           const std::vector<int>& skin_joint_of_bone,
                           std::uint16_t* j_out,
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

void append_stick_box(
    const Transform& X, const Vector3& a, const Vector3& b, double r, int joint, MeshArrays& out) {
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
    const auto base = static_cast<std::uint32_t>(out.pos.size() / 3);
    const Vector3 n_W = X.R * (basis * f[0]);
    for (int c = 0; c < 4; ++c) {
      const double s1 = (c == 1 || c == 2) ? 1 : -1;
      const double s2 = c >= 2 ? 1 : -1;
      const Eigen::Vector3d k = f[0] + s1 * f[1] + s2 * f[2];
      const Vector3 p_W = X * Vector3((k[2] > 0 ? b0 : a0) + r * (k[0] * u + k[1] * w));
      for (int t = 0; t < 3; ++t) out.pos.push_back(static_cast<float>(p_W[t]));
      for (int t = 0; t < 3; ++t) out.nrm.push_back(static_cast<float>(n_W[t]));
      out.jnt.insert(out.jnt.end(), {static_cast<std::uint16_t>(joint), 0, 0, 0});
    }
    out.idx.insert(out.idx.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
}

void append_link_sticks(
    const Model& model, int i, const Transform& X_bind, double r, MeshArrays& out) {
  append_stick_box(X_bind, Vector3::Zero(), Vector3::Zero(), 1.5 * r, i - 1, out);
  for (int c = i + 1; c < model.subtree_end[i]; ++c) {
    if (model.parent[c] == i)
      append_stick_box(X_bind, Vector3::Zero(), model.X_PJ[c].p, r, i - 1, out);
  }
}

std::vector<float> rigid_weights(const MeshArrays& m) {
  std::vector<float> wgt(4 * (m.pos.size() / 3), 0.0f);
  for (std::size_t v = 0; v < wgt.size(); v += 4) wgt[v] = 1.0f;
  return wgt;
}

}  // namespace io::gltf_detail
