#include "io/assimp_scene.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace io::assimp_detail {

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

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

SceneNodes index_nodes(const aiScene& scene) {
  SceneNodes out;
  std::vector<Node>& nodes = out.nodes;
  std::vector<std::pair<const aiNode*, int>> stack{{scene.mRootNode, -1}};
  while (!stack.empty()) {
    auto [ai, parent] = stack.back();
    stack.pop_back();
    if (nodes.size() >= static_cast<std::size_t>(core::kMaxLinks) * 4) {
      throw std::runtime_error("the file has more than " + std::to_string(core::kMaxLinks * 4) +
                               " nodes");
    }
    Node n;
    n.ai = ai;
    n.parent = parent;
    n.depth = parent < 0 ? 0 : nodes[parent].depth + 1;
    n.name = ai->mName.C_Str();
    if (!finite_matrix(ai->mTransformation)) {
      throw std::runtime_error("node '" + n.name + "' has a non-finite transform");
    }
    n.local_rest = to_eigen(ai->mTransformation);
    n.global_rest = parent < 0 ? n.local_rest : Matrix4(nodes[parent].global_rest * n.local_rest);
    aiVector3D s, t;
    aiQuaternion r;
    ai->mTransformation.Decompose(s, r, t);
    n.rest_t = Vector3(t.x, t.y, t.z);
    n.rest_r = Quaternion(r.w, r.x, r.y, r.z).normalized();
    n.rest_s = Vector3(s.x, s.y, s.z);
    const int self = static_cast<int>(nodes.size());
    nodes.push_back(n);
    out.by_name.emplace(n.name, self);
    // children pushed last-first, so they are visited in the file's order
    for (unsigned c = ai->mNumChildren; c-- > 0;) stack.push_back({ai->mChildren[c], self});
  }
  return out;
}

namespace {

// FBX: centimetres per file unit, from the file's UnitScaleFactor (float or double), else 1
double fbx_unit_factor(const aiMetadata* md) {
  double factor = 1;
  if (md != nullptr) {
    float f = 0;
    double d = 0;
    if (md->Get("UnitScaleFactor", f) && std::isfinite(f) && f > 0) {
      factor = f;
    } else if (md->Get("UnitScaleFactor", d) && std::isfinite(d) && d > 0) {
      factor = d;
    }
  }
  return factor;
}

// FBX: our axes as signed file axes (x = coord, y = up, z = front); the axes are kept as stored
// when the file's choice is not a rotation
void fbx_axes(const aiMetadata* md, WorldAxes& out, Warnings& warnings) {
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
    out.axes = C;
  } else {
    warnings.add("the FBX axis system (up " + std::to_string(up) + ", front " +
                 std::to_string(front) + ", coord " + std::to_string(coord) +
                 ") is not a rotation; axes kept as stored");
  }
}

}  // namespace

WorldAxes world_axes(const aiScene& scene, const std::string& ext, Warnings& warnings) {
  WorldAxes out;
  if (ext == ".fbx") {
    out.unit_scale = fbx_unit_factor(scene.mMetaData) / 100.0;
    fbx_axes(scene.mMetaData, out, warnings);
  }
  out.A.setIdentity();
  out.A.topLeftCorner<3, 3>() = out.unit_scale * out.axes;
  return out;
}

SkinnedMeshes collect_bones(const aiScene& scene, const SceneNodes& nodes, Warnings& warnings) {
  SkinnedMeshes out;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || mesh->mNumBones == 0) continue;
    if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
    SourceMesh sm;
    sm.mesh = mesh;
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
      const aiBone* bone = mesh->mBones[b];
      const auto it = nodes.by_name.find(bone->mName.C_Str());
      if (it == nodes.by_name.end()) {
        warnings.add("mesh '" + std::string(mesh->mName.C_Str()) + "': bone '" +
                     bone->mName.C_Str() + "' has no node; its weights are dropped");
        sm.bone_node.push_back(-1);
        continue;
      }
      if (!finite_matrix(bone->mOffsetMatrix)) {
        throw std::runtime_error("bone '" + std::string(bone->mName.C_Str()) +
                                 "' has a non-finite offset matrix");
      }
      const int node = it->second;
      sm.bone_node.push_back(node);
      if (out.offset.count(node) == 0) {
        out.offset[node] = to_eigen(bone->mOffsetMatrix);
        out.offset_mesh[node] = static_cast<int>(out.meshes.size());
      }
    }
    out.meshes.push_back(sm);
  }
  return out;
}

Matrix4 offset_for(const SourceMesh& sm, int node) {
  for (unsigned b = 0; b < sm.mesh->mNumBones; ++b) {
    if (sm.bone_node[b] == node) return to_eigen(sm.mesh->mBones[b]->mOffsetMatrix);
  }
  return Matrix4::Identity();
}

void mesh_bind_spaces(const SceneNodes& scene, SkinnedMeshes& skinned) {
  const std::vector<Node>& nodes = scene.nodes;
  for (SourceMesh& sm : skinned.meshes) {
    if (sm.carrier_node >= 0) continue;  // placed by place_carried_meshes
    int top = -1;
    for (int node : sm.bone_node) {
      if (node >= 0 && (top < 0 || nodes[node].depth < nodes[top].depth)) top = node;
    }
    sm.B = top < 0 ? Matrix4(Matrix4::Identity())
                   : Matrix4(nodes[top].global_rest * offset_for(sm, top));
  }
}

}  // namespace io::assimp_detail
