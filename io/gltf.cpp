#include "io/gltf.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_set>

#include "core/clip.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "io/atomic_file.hpp"
#include "io/gltf_buffer.hpp"
#include "io/gltf_mesh.hpp"
#include "io/gltf_shape_mesh.hpp"

namespace io {

using namespace gltf_detail;

namespace {

using core::JointType;

constexpr int kArrayBuffer = TINYGLTF_TARGET_ARRAY_BUFFER;

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

std::vector<double> vec3(const Vector3& v) { return {v.x(), v.y(), v.z()}; }
// a rotation as glTF writes it: x, y, z, w
std::vector<double> xyzw(const Quaternion& q) { return {q.x(), q.y(), q.z(), q.w()}; }

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
LocalPose local_pose(const Model& model,
                     const std::vector<Quaternion>& placement,
                     int i,
                     const Eigen::VectorXd& q) {
  const int iq = model.idx_q[i];
  const Transform& X = model.X_PJ[i];
  switch (model.joint_type[i]) {
    case JointType::kFixed:
      return {placement[i], X.p};
    case JointType::kRevolute:
      return {placement[i] * Quaternion(Eigen::AngleAxisd(q[iq], model.axis[i])), X.p};
    case JointType::kPrismatic:
      return {placement[i], X.p + X.R * (model.axis[i] * q[iq])};
    case JointType::kSpherical:
      return {placement[i] * core::quaternion_at(q, iq), X.p};
    case JointType::kFree:
      return {placement[i] * core::quaternion_at(q, iq + 3), X.p + X.R * q.segment<3>(iq)};
  }
  return {placement[i], X.p};
}

bool animates_rotation(JointType t) {
  return t == JointType::kRevolute || t == JointType::kSpherical || t == JointType::kFree;
}
bool animates_translation(JointType t) {
  return t == JointType::kPrismatic || t == JointType::kFree;
}

void check_input(const Model& model,
                 const Clip* clip,
                 const SkinnedMesh* skin,
                 const GltfExportOptions& options) {
  const int nlinks = model.nlinks();
  if (nlinks < 1) throw std::invalid_argument("glTF export: the model has no links");
  if (nlinks > 65535) throw std::invalid_argument("glTF export: more than 65535 links");
  if (clip != nullptr) {
    const std::string e = core::check_clip(model, *clip);
    if (!e.empty()) throw std::invalid_argument("glTF export: clip: " + e);
  }
  if (skin != nullptr) check_skin(model, *skin);
  const bool sticks = options.stick_figure || options.shape_mesh;
  if (sticks && !(options.stick_radius > 0 && std::isfinite(options.stick_radius))) {
    throw std::invalid_argument("glTF export: stick_radius must be a finite number > 0");
  }
}

// the document while it is built
struct Parts {
  Parts(const Model& m, std::string scene_name)
      : model(m), name(std::move(scene_name)), node_name(node_names(m)), placement(m.njoints) {
    for (int i = 1; i < m.njoints; ++i) placement[i] = Quaternion(m.X_PJ[i].R).normalized();
  }

  const Model& model;
  std::string name;                     // scene, skeleton and animation name
  std::vector<std::string> node_name;   // per link
  std::vector<Quaternion> placement;    // per link: X_PJ's rotation as a unit quaternion
  std::vector<Transform> inverse_bind;  // per link
  tinygltf::Model doc;
  BufferBuilder buf{doc};
};

// nodes: link i is node i - 1, at the neutral configuration (the bind pose); roots are scene
// nodes
void add_link_nodes(Parts& d, const Eigen::VectorXd& q0) {
  const Model& model = d.model;
  d.doc.scenes.resize(1);
  d.doc.nodes.resize(model.nlinks());
  for (int i = 1; i < model.njoints; ++i) {
    const LocalPose X = local_pose(model, d.placement, i, q0);
    tinygltf::Node& n = d.doc.nodes[i - 1];
    n.name = d.node_name[i];
    n.translation = vec3(X.translation);
    n.rotation = xyzw(X.rotation.normalized());
    if (d.node_name[i] != model.link_name[i]) {
      n.extras =
          tinygltf::Value(tinygltf::Value::Object{{"link", tinygltf::Value(model.link_name[i])}});
    }
    if (model.parent[i] == 0) d.doc.scenes[0].nodes.push_back(i - 1);
    if (model.parent[i] >= 1) d.doc.nodes[model.parent[i] - 1].children.push_back(i - 1);
  }
}

// skin 0: every link, with inverse bind matrices d.inverse_bind
void add_skin(Parts& d) {
  std::vector<float> ibm;
  ibm.reserve(16 * d.model.nlinks());
  tinygltf::Skin skin;
  for (int i = 1; i < d.model.njoints; ++i) {
    append_mat4(d.inverse_bind[i], ibm);
    skin.joints.push_back(i - 1);
  }
  skin.name = d.name + "_skeleton";
  skin.inverseBindMatrices = d.buf.add_floats(ibm, 16, TINYGLTF_TYPE_MAT4, false, 0);
  skin.skeleton = d.doc.scenes[0].nodes[0];
  d.doc.skins.push_back(std::move(skin));
}

// a mesh of one triangle primitive (POSITION with bounds, NORMAL, JOINTS_0, WEIGHTS_0, indices)
// and its material
void add_mesh(Parts& d,
              const std::string& name,
              const MeshArrays& m,
              const std::vector<float>& wgt,
              const std::vector<double>& color,
              double roughness) {
  const std::size_t n = m.pos.size() / 3;
  tinygltf::Primitive p;
  p.attributes["POSITION"] = d.buf.add_floats(m.pos, 3, TINYGLTF_TYPE_VEC3, true, kArrayBuffer);
  p.attributes["NORMAL"] = d.buf.add_floats(m.nrm, 3, TINYGLTF_TYPE_VEC3, false, kArrayBuffer);
  p.attributes["JOINTS_0"] = d.buf.add_integers(m.jnt, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                                TINYGLTF_TYPE_VEC4, n, kArrayBuffer);
  p.attributes["WEIGHTS_0"] = d.buf.add_floats(wgt, 4, TINYGLTF_TYPE_VEC4, false, kArrayBuffer);
  if (!m.idx.empty()) p.indices = d.buf.add_indices(m.idx, n);
  p.material = static_cast<int>(d.doc.materials.size());
  p.mode = TINYGLTF_MODE_TRIANGLES;  // tinygltf always writes the mode, -1 when unset
  tinygltf::Material mat;
  mat.name = name;
  mat.pbrMetallicRoughness.baseColorFactor = color;
  mat.pbrMetallicRoughness.metallicFactor = 0.0;
  mat.pbrMetallicRoughness.roughnessFactor = roughness;
  d.doc.materials.push_back(std::move(mat));
  tinygltf::Mesh mesh;
  mesh.name = name;
  mesh.primitives.push_back(std::move(p));
  d.doc.meshes.push_back(std::move(mesh));
}

// the images of the skinned mesh's textures, stored in the buffer, each a texture sampled with
// glTF's defaults (linear, repeat); returns the texture index of each
void add_textures(Parts& d, const SkinnedMesh& skin) {
  for (const core::MeshTexture& t : skin.textures) {
    tinygltf::Image image;
    image.bufferView = d.buf.add_view(t.bytes.data(), t.bytes.size(), 0);
    image.mimeType = t.mime_type;
    d.doc.images.push_back(std::move(image));
    tinygltf::Texture texture;
    texture.source = static_cast<int>(d.doc.images.size()) - 1;
    d.doc.textures.push_back(std::move(texture));
  }
}

// The skinned mesh: one primitive per part (its triangles, a material of its base colour,
// clamped to [0, 1], and texture), all sharing the vertex attributes; TEXCOORD_0 with glTF's v
// (from the image's top edge).
void add_skinned_mesh(Parts& d, const SkinnedMesh& skin) {
  std::vector<int> skin_joint_of_bone;
  for (int link : skin.bones) skin_joint_of_bone.push_back(link - 1);
  const size_t n = skin.positions.size();
  MeshArrays m;
  std::vector<float> wgt(4 * n);
  m.jnt.resize(4 * n);
  const std::vector<Eigen::Vector3f> normals = unit_normals(skin);
  for (size_t v = 0; v < n; ++v) {
    m.pos.insert(m.pos.end(),
                 {skin.positions[v].x(), skin.positions[v].y(), skin.positions[v].z()});
    m.nrm.insert(m.nrm.end(), {normals[v].x(), normals[v].y(), normals[v].z()});
    normalized_influences(skin.joints[v], skin.weights[v], skin_joint_of_bone, &m.jnt[4 * v],
                          &wgt[4 * v]);
  }
  std::map<std::string, int> attributes;
  attributes["POSITION"] = d.buf.add_floats(m.pos, 3, TINYGLTF_TYPE_VEC3, true, kArrayBuffer);
  attributes["NORMAL"] = d.buf.add_floats(m.nrm, 3, TINYGLTF_TYPE_VEC3, false, kArrayBuffer);
  attributes["JOINTS_0"] = d.buf.add_integers(m.jnt, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                              TINYGLTF_TYPE_VEC4, n, kArrayBuffer);
  attributes["WEIGHTS_0"] = d.buf.add_floats(wgt, 4, TINYGLTF_TYPE_VEC4, false, kArrayBuffer);
  if (!skin.uvs.empty()) {
    std::vector<float> uv;
    uv.reserve(2 * n);
    for (const auto& t : skin.uvs) uv.insert(uv.end(), {t.x(), 1.0f - t.y()});
    attributes["TEXCOORD_0"] = d.buf.add_floats(uv, 2, TINYGLTF_TYPE_VEC2, false, kArrayBuffer);
  }
  const int first_texture = static_cast<int>(d.doc.textures.size());
  add_textures(d, skin);

  std::vector<core::MeshPart> parts = skin.parts;
  if (parts.empty()) {
    parts.push_back({0, static_cast<int>(skin.triangles.size()), skin.base_color, -1});
  }
  tinygltf::Mesh mesh;
  mesh.name = skin.name.empty() ? "skin" : skin.name;
  for (size_t k = 0; k < parts.size(); ++k) {
    const core::MeshPart& part = parts[k];
    // a part without triangles draws nothing, but a mesh keeps one primitive (glTF needs one)
    const bool last_chance = k + 1 == parts.size() && mesh.primitives.empty();
    if (part.triangle_count == 0 && !last_chance) continue;
    std::vector<std::uint32_t> idx;
    idx.reserve(3 * static_cast<size_t>(part.triangle_count));
    for (int t = part.first_triangle; t < part.first_triangle + part.triangle_count; ++t) {
      for (int c : skin.triangles[t]) idx.push_back(static_cast<std::uint32_t>(c));
    }
    tinygltf::Primitive p;
    p.attributes = attributes;
    if (!idx.empty()) p.indices = d.buf.add_indices(idx, n);
    p.material = static_cast<int>(d.doc.materials.size());
    // tinygltf always writes the mode, -1 when unset; a mesh without triangles is its points
    p.mode = idx.empty() ? TINYGLTF_MODE_POINTS : TINYGLTF_MODE_TRIANGLES;
    tinygltf::Material mat;
    mat.name = mesh.name + (parts.size() > 1 ? "_" + std::to_string(k) : std::string());
    const Eigen::Vector4f c = part.base_color.cwiseMax(0.0f).cwiseMin(1.0f);
    mat.pbrMetallicRoughness.baseColorFactor = {c[0], c[1], c[2], c[3]};
    mat.pbrMetallicRoughness.metallicFactor = 0.0;
    mat.pbrMetallicRoughness.roughnessFactor = 0.8;
    if (part.texture >= 0 && !skin.uvs.empty()) {
      mat.pbrMetallicRoughness.baseColorTexture.index = first_texture + part.texture;
    }
    d.doc.materials.push_back(std::move(mat));
    mesh.primitives.push_back(std::move(p));
  }
  d.doc.meshes.push_back(std::move(mesh));
}

// the stick figure: a box from each link to each child, a cube on each link origin
void add_stick_figure(Parts& d, double r) {
  MeshArrays m;
  for (int i = 1; i < d.model.njoints; ++i) {
    append_link_sticks(d.model, i, d.inverse_bind[i].inverse(), r, m);
  }
  add_mesh(d, "stick_figure", m, rigid_weights(m), {0.55, 0.65, 0.8, 1.0}, 0.6);
}

// the shape mesh: every link's primitive shapes at the bind pose (stick boxes for a link
// without any), one light grey material
void add_shape_mesh(Parts& d, double r) {
  std::vector<Transform> X_bind(d.model.njoints);
  for (int i = 1; i < d.model.njoints; ++i) X_bind[i] = d.inverse_bind[i].inverse();
  const MeshArrays m = shape_mesh(d.model, X_bind, r);
  add_mesh(d, "shapes", m, rigid_weights(m), {0.78, 0.78, 0.8, 1.0}, 0.7);
}

// key times k · frame_time as floats, which must strictly increase
std::vector<float> key_times(const Clip& clip) {
  const int nf = clip.size();
  std::vector<float> times(nf);
  for (int k = 0; k < nf; ++k) {
    times[k] = static_cast<float>(k * clip.frame_time);
    if (k > 0 && !(times[k] > times[k - 1])) {
      throw std::invalid_argument(
          "glTF export: frame time " + std::to_string(clip.frame_time) +
          " s is too short: " + "frames " + std::to_string(k - 1) + " and " + std::to_string(k) +
          " get the same single-precision key time (rule: key times strictly increase)");
    }
  }
  return times;
}

// the keys of link i over the clip: rotations (x, y, z, w) hemisphere-continuous, translations
void link_keys(
    const Parts& d, int i, const Clip& clip, std::vector<float>& rot, std::vector<float>& tra) {
  const JointType t = d.model.joint_type[i];
  rot.clear();
  tra.clear();
  Quaternion prev(1, 0, 0, 0);
  for (int k = 0; k < clip.size(); ++k) {
    const LocalPose X = local_pose(d.model, d.placement, i, clip.frames[k]);
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
      tra.insert(tra.end(),
                 {static_cast<float>(X.translation.x()), static_cast<float>(X.translation.y()),
                  static_cast<float>(X.translation.z())});
    }
  }
}

// the animation: one LINEAR sampler per animated channel, one key per frame
void add_animation(Parts& d, const Clip& clip) {
  const int input = d.buf.add_floats(key_times(clip), 1, TINYGLTF_TYPE_SCALAR, true, 0);
  tinygltf::Animation an;
  an.name = d.name;
  std::vector<float> rot, tra;
  for (int i = 1; i < d.model.njoints; ++i) {
    const JointType t = d.model.joint_type[i];
    if (!animates_rotation(t) && !animates_translation(t)) continue;
    link_keys(d, i, clip, rot, tra);
    auto add_channel = [&](int output, const char* path) {
      tinygltf::AnimationChannel ch;
      ch.sampler = static_cast<int>(an.samplers.size());
      ch.target_node = i - 1;
      ch.target_path = path;
      an.channels.push_back(std::move(ch));
      tinygltf::AnimationSampler s;
      s.input = input;
      s.output = output;
      s.interpolation = "LINEAR";
      an.samplers.push_back(std::move(s));
    };
    if (animates_translation(t)) {
      add_channel(d.buf.add_floats(tra, 3, TINYGLTF_TYPE_VEC3, false, 0), "translation");
    }
    if (animates_rotation(t)) {
      add_channel(d.buf.add_floats(rot, 4, TINYGLTF_TYPE_VEC4, false, 0), "rotation");
    }
  }
  if (!an.channels.empty()) d.doc.animations.push_back(std::move(an));
}

tinygltf::Model build(const Model& model,
                      const Clip* clip,
                      const SkinnedMesh* skin,
                      const GltfExportOptions& options) {
  if (skin != nullptr && skin->empty()) skin = nullptr;
  check_input(model, clip, skin, options);
  Parts d(model, options.name.empty() ? model.name : options.name);
  d.doc.asset.version = "2.0";
  d.doc.asset.generator = options.generator;
  d.doc.defaultScene = 0;
  const Eigen::VectorXd q0 = core::neutral_configuration(model);
  add_link_nodes(d, q0);
  d.doc.scenes[0].name = d.name;
  // inverse bind: of the neutral pose, or the mesh's own for its bones
  core::Data data(model);
  core::forward_kinematics(model, data, q0);
  d.inverse_bind.resize(model.njoints);
  for (int i = 1; i < model.njoints; ++i) d.inverse_bind[i] = data.X_W[i].inverse();
  if (skin != nullptr) {
    for (size_t b = 0; b < skin->bones.size(); ++b) {
      d.inverse_bind[skin->bones[b]] = skin->inverse_bind[b];
    }
  }
  add_skin(d);
  if (skin != nullptr) add_skinned_mesh(d, *skin);
  // the shape mesh, or the stick figure in its place when the model has no primitive shape
  const bool shapes = options.shape_mesh && has_primitive_shapes(model);
  if (shapes) add_shape_mesh(d, options.stick_radius);
  if (options.stick_figure || (options.shape_mesh && !shapes)) {
    add_stick_figure(d, options.stick_radius);
  }
  // mesh nodes: roots with an identity transform, skinned by skin 0
  for (size_t m = 0; m < d.doc.meshes.size(); ++m) {
    tinygltf::Node n;
    n.name = d.doc.meshes[m].name;
    n.mesh = static_cast<int>(m);
    n.skin = 0;
    d.doc.nodes.push_back(std::move(n));
    d.doc.scenes[0].nodes.push_back(static_cast<int>(d.doc.nodes.size()) - 1);
  }
  if (clip != nullptr && !clip->empty()) add_animation(d, *clip);
  return std::move(d.doc);
}

// .gltf text (indented JSON, the buffer as a base64 data URI, a final newline) or GLB bytes
// (compact JSON chunk, BIN chunk, both padded to 4 bytes), as tinygltf writes them
std::string serialize(const tinygltf::Model& doc, bool binary) {
  std::ostringstream out;
  if (!tinygltf::TinyGLTF().WriteGltfSceneToStream(&doc, out, !binary, binary)) {
    throw std::runtime_error("glTF export: tinygltf could not write the document");
  }
  return out.str();
}

}  // namespace

std::string write_gltf(const Model& model,
                       const Clip* clip,
                       const SkinnedMesh* skin,
                       const GltfExportOptions& options) {
  return serialize(build(model, clip, skin, options), false);
}

std::vector<std::uint8_t> write_glb(const Model& model,
                                    const Clip* clip,
                                    const SkinnedMesh* skin,
                                    const GltfExportOptions& options) {
  const std::string bytes = serialize(build(model, clip, skin, options), true);
  // tinygltf's GLB header holds 32-bit lengths, which wrap past 4 GiB
  if (bytes.size() > std::numeric_limits<std::uint32_t>::max()) {
    throw std::invalid_argument("glTF export: the GLB would exceed 4 GiB");
  }
  return std::vector<std::uint8_t>(bytes.begin(), bytes.end());
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
