// Tests for io/gltf.hpp: our export of human48 read back by our own minimal reader
// (tests/io/gltf_reader.hpp), by three.js GLTFLoader in Node, by the Khronos validator and
// by assimp's CLI; node world matrices are compared with core::forward_kinematics per frame.
#include "io/gltf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/io/gltf_reader.hpp"

namespace {

using core::JointType;
using core::Quaternion;
using core::Vector3;
using gltf_test::Json;

// float keys and a float buffer: world poses agree with FK to this (metres, rotation entries)
constexpr double kFkTolerance = 1e-6;
// three.js samples in float32 buffers (ecosystem.md §2 checklist: 1e-5 m)
constexpr double kThreeTolerance = 1e-5;
// every info or warning the validator may report on a file we write, and why
const std::map<std::string, std::string> kAllowedIssues = {
    {"UNUSED_OBJECT", "skeleton-only export: skins[0] lists every joint but no mesh uses it"},
};

// Several hundred frames of varied motion: the root walks, turns four times round (the stored
// root quaternion is kept at w >= 0, so its sign jumps each time the turn passes 180°), every
// spherical joint swings up to 1.5 rad with a twist that sweeps past ±π on every third joint, and
// stored quaternion signs are flipped at random frames: the exporter must make them continuous.
core::Clip synthetic_clip(const core::Model& m, int nframes, double dt = 1.0 / 30.0) {
  core::Clip clip;
  clip.frame_time = dt;
  for (int k = 0; k < nframes; ++k) {
    const double t = k * dt;
    Eigen::VectorXd q = core::neutral_configuration(m);
    for (int i = 1; i < m.njoints; ++i) {
      const int iq = m.idx_q[i];
      const double ph = 0.7 * i;
      switch (m.joint_type[i]) {
        case JointType::kFixed:
          break;
        case JointType::kRevolute:
          q[iq] = 1.2 * std::sin((0.9 + 0.1 * i) * t + ph);
          break;
        case JointType::kPrismatic:
          q[iq] = 0.1 * std::sin(t + ph);
          break;
        case JointType::kSpherical: {
          Vector3 w(1.5 * std::sin(0.8 * t + ph), 0.9 * std::sin(1.3 * t + 2 * ph),
                    1.1 * std::sin(0.5 * t + 3 * ph));
          Quaternion r = core::quaternion_exp(w);
          if (i % 3 == 0) r = r * Quaternion(Eigen::AngleAxisd(2.1 * t, Vector3::UnitX()));
          if ((k * 7 + i) % 5 == 0) r.coeffs() = -r.coeffs();
          core::set_quaternion_at(q, iq, r.normalized());
          break;
        }
        case JointType::kFree: {
          q.segment<3>(iq) =
              Vector3(0.8 * std::sin(0.7 * t), 0.05 * std::sin(3 * t), 1.5 * std::sin(0.21 * t));
          Quaternion r = Quaternion(Eigen::AngleAxisd(1.3 * t, Vector3::UnitY())) *
                         Quaternion(Eigen::AngleAxisd(0.3 * std::sin(1.1 * t), Vector3::UnitX()));
          if (r.w() < 0) r.coeffs() = -r.coeffs();
          core::set_quaternion_at(q, iq + 3, r.normalized());
          break;
        }
      }
    }
    clip.frames.push_back(q);
  }
  return clip;
}

// glTF node index of each link, found by name (or by extras.link when the name was sanitized)
std::vector<int> node_of_link(const core::Model& m, const Json& doc) {
  std::vector<int> out(m.njoints, -1);
  const Json& nodes = doc.at("nodes");
  for (size_t n = 0; n < nodes.size(); ++n) {
    std::string link = nodes[n].value("name", "");
    if (nodes[n].contains("extras") && nodes[n]["extras"].contains("link")) {
      link = nodes[n]["extras"]["link"];
    }
    const int i = m.link_index(link);
    if (i > 0 && !nodes[n].contains("mesh")) out[i] = static_cast<int>(n);
  }
  return out;
}

double max_abs(const Eigen::MatrixXd& a) { return a.cwiseAbs().maxCoeff(); }

// world matrices of every link node at every key equal FK of the clip frame
void expect_keys_match_fk(const core::Model& m,
                          const core::Clip& clip,
                          const gltf_test::Document& doc,
                          double tol) {
  const std::vector<int> node = node_of_link(m, doc.json);
  for (int i = 1; i < m.njoints; ++i) ASSERT_GE(node[i], 0) << "no node for " << m.link_name[i];
  const auto worlds = gltf_test::world_matrices_at_keys(doc, 0);
  ASSERT_EQ(static_cast<int>(worlds.size()), clip.size());
  core::Data data(m);
  double worst = 0;
  for (int k = 0; k < clip.size(); ++k) {
    core::forward_kinematics(m, data, clip.frames[k]);
    for (int i = 1; i < m.njoints; ++i) {
      const Eigen::Matrix4d& W = worlds[k][node[i]];
      const double e = std::max(max_abs(W.topLeftCorner<3, 3>() - data.X_W[i].R),
                                max_abs(W.topRightCorner<3, 1>() - data.X_W[i].p));
      worst = std::max(worst, e);
      ASSERT_LE(e, tol) << "frame " << k << " link " << m.link_name[i];
    }
  }
  std::printf("  node world matrices vs FK over %d frames x %d links: max error %.3g\n",
              clip.size(), m.nlinks(), worst);
}

// the structure a file of ours must have: TRS only, LINEAR, unit continuous quaternions
void expect_structure(const core::Model& m,
                      const core::Clip* clip,
                      const gltf_test::Document& doc) {
  const Json& j = doc.json;
  std::vector<std::string> errors;
  gltf_test::check_layout(doc, errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  EXPECT_EQ(j["asset"]["version"], "2.0");
  EXPECT_TRUE(j["asset"].contains("generator"));
  for (const Json& n : j["nodes"]) EXPECT_FALSE(n.contains("matrix")) << n.dump();
  // the skin lists every link
  ASSERT_EQ(j["skins"].size(), 1u);
  std::set<int> joints;
  for (const Json& x : j["skins"][0]["joints"]) joints.insert(x.get<int>());
  EXPECT_EQ(static_cast<int>(joints.size()), m.nlinks());
  const std::vector<int> node = node_of_link(m, j);
  for (int i = 1; i < m.njoints; ++i) EXPECT_EQ(joints.count(node[i]), 1u) << m.link_name[i];
  const Json& ibm = j["accessors"][j["skins"][0]["inverseBindMatrices"].get<int>()];
  EXPECT_EQ(ibm["count"].get<int>(), m.nlinks());
  EXPECT_EQ(ibm["type"], "MAT4");
  if (clip == nullptr) {
    EXPECT_FALSE(j.contains("animations"));
    return;
  }
  ASSERT_EQ(j["animations"].size(), 1u);
  const Json& an = j["animations"][0];
  int expected_channels = 0;
  for (int i = 1; i < m.njoints; ++i) {
    const JointType t = m.joint_type[i];
    expected_channels +=
        (t == JointType::kRevolute || t == JointType::kSpherical || t == JointType::kFree);
    expected_channels += (t == JointType::kPrismatic || t == JointType::kFree);
  }
  EXPECT_EQ(static_cast<int>(an["channels"].size()), expected_channels);
  EXPECT_EQ(an["samplers"].size(), an["channels"].size());
  std::set<std::pair<int, std::string>> targets;
  for (const Json& ch : an["channels"]) {
    const std::pair<int, std::string> target{ch["target"]["node"].get<int>(),
                                             ch["target"]["path"].get<std::string>()};
    EXPECT_TRUE(targets.insert(target).second);
  }
  for (const Json& s : an["samplers"]) {
    EXPECT_EQ(s["interpolation"], "LINEAR");
    const std::vector<double> times = gltf_test::read_accessor(doc, s["input"]);
    ASSERT_EQ(static_cast<int>(times.size()), clip->size());
    EXPECT_EQ(times[0], 0.0);
    for (size_t k = 1; k < times.size(); ++k) ASSERT_GT(times[k], times[k - 1]);
    EXPECT_NEAR(times.back(), clip->duration(), 1e-5);
  }
  for (const Json& ch : an["channels"]) {
    if (ch["target"]["path"] != "rotation") continue;
    const std::vector<double> v =
        gltf_test::read_accessor(doc, an["samplers"][ch["sampler"].get<int>()]["output"]);
    for (size_t k = 0; k < v.size() / 4; ++k) {
      const Eigen::Vector4d a(v[4 * k], v[4 * k + 1], v[4 * k + 2], v[4 * k + 3]);
      ASSERT_NEAR(a.norm(), 1.0, 1e-6) << "key " << k;
      if (k == 0) continue;
      const Eigen::Vector4d b(v[4 * k - 4], v[4 * k - 3], v[4 * k - 2], v[4 * k - 1]);
      ASSERT_GE(a.dot(b), 0.0) << "quaternion keys " << k - 1 << " and " << k
                               << " are in opposite hemispheres";
    }
  }
}

std::shared_ptr<const core::Model> human() { return core::build_human_figure({}); }

TEST(GltfExport, Human48ClipMatchesForwardKinematicsInGltfAndGlb) {
  const auto m = human();
  const core::Clip clip = synthetic_clip(*m, 600);
  {
    std::vector<std::string> errors;
    const gltf_test::Document doc =
        gltf_test::parse_gltf(io::write_gltf(*m, &clip, nullptr), errors);
    for (const auto& e : errors) ADD_FAILURE() << e;
    expect_structure(*m, &clip, doc);
    expect_keys_match_fk(*m, clip, doc, kFkTolerance);
  }
  {
    std::vector<std::string> errors;
    const gltf_test::Document doc = gltf_test::parse_glb(io::write_glb(*m, &clip, nullptr), errors);
    for (const auto& e : errors) ADD_FAILURE() << e;
    expect_structure(*m, &clip, doc);
    expect_keys_match_fk(*m, clip, doc, kFkTolerance);
  }
}

TEST(GltfExport, QuaternionKeysAreMadeContinuousWhereTheClipJumps) {
  const auto m = human();
  const core::Clip clip = synthetic_clip(*m, 300);
  // the clip itself jumps hemispheres (that is the point of the test input)
  int jumps = 0;
  const int iq = m->idx_q[1] + 3;
  for (int k = 1; k < clip.size(); ++k) {
    jumps += core::quaternion_at(clip.frames[k], iq)
                 .coeffs()
                 .dot(core::quaternion_at(clip.frames[k - 1], iq).coeffs()) < 0;
  }
  ASSERT_GT(jumps, 0);
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::parse_glb(io::write_glb(*m, &clip, nullptr), errors);
  // the root's rotation keys: continuous, and each equals ± the frame's rotation
  const Json& an = doc.json["animations"][0];
  for (const Json& ch : an["channels"]) {
    if (ch["target"]["node"] != 0 || ch["target"]["path"] != "rotation") continue;
    const auto v =
        gltf_test::read_accessor(doc, an["samplers"][ch["sampler"].get<int>()]["output"]);
    int flipped = 0;
    for (int k = 0; k < clip.size(); ++k) {
      const Quaternion r = Quaternion(m->X_PJ[1].R) * core::quaternion_at(clip.frames[k], iq);
      const double d =
          r.x() * v[4 * k] + r.y() * v[4 * k + 1] + r.z() * v[4 * k + 2] + r.w() * v[4 * k + 3];
      EXPECT_NEAR(std::abs(d), 1.0, 1e-6);
      flipped += d < 0;
      if (k > 0) {
        EXPECT_GE(v[4 * k] * v[4 * k - 4] + v[4 * k + 1] * v[4 * k - 3] +
                      v[4 * k + 2] * v[4 * k - 2] + v[4 * k + 3] * v[4 * k - 1],
                  0.0);
      }
    }
    EXPECT_GT(flipped, 0) << "no key needed its sign flipped";
  }
}

TEST(GltfExport, WithoutClipTheNodesHoldTheNeutralPoseAndTheSkinItsInverse) {
  const auto m = human();
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::parse_glb(io::write_glb(*m, nullptr, nullptr), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  expect_structure(*m, nullptr, doc);
  core::Clip neutral;
  neutral.frames.push_back(core::neutral_configuration(*m));
  expect_keys_match_fk(*m, neutral, doc, kFkTolerance);
  // inverse bind matrices: inverse of the neutral world pose, bottom row exactly 0 0 0 1
  core::Data data(*m);
  core::forward_kinematics(*m, data, neutral.frames[0]);
  const std::vector<int> node = node_of_link(*m, doc.json);
  const auto& skin = doc.json["skins"][0];
  const auto ibm = gltf_test::read_accessor(doc, skin["inverseBindMatrices"]);
  for (size_t j = 0; j < skin["joints"].size(); ++j) {
    Eigen::Matrix4d M;
    for (int k = 0; k < 16; ++k) M(k % 4, k / 4) = ibm[16 * j + k];
    EXPECT_EQ(M.row(3), Eigen::RowVector4d(0, 0, 0, 1));
    const int n = skin["joints"][j];
    int link = -1;
    for (int i = 1; i < m->njoints; ++i)
      if (node[i] == n) link = i;
    ASSERT_GT(link, 0);
    Eigen::Matrix4d W = Eigen::Matrix4d::Identity();
    W.topLeftCorner<3, 3>() = data.X_W[link].R;
    W.topRightCorner<3, 1>() = data.X_W[link].p;
    EXPECT_LE(max_abs(M * W - Eigen::Matrix4d::Identity()), 1e-6) << m->link_name[link];
  }
}

TEST(GltfExport, FixedAndPrismaticJointsOnTheBranchingTree) {
  const auto m = fixtures::branching_tree();
  core::Clip clip;
  for (int k = 0; k < 50; ++k) clip.frames.push_back(core::random_configuration(*m, 100 + k));
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::parse_gltf(io::write_gltf(*m, &clip, nullptr), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  expect_structure(*m, &clip, doc);
  expect_keys_match_fk(*m, clip, doc, kFkTolerance);
}

// a tube of 8-sided rings along each bone of human48, blended between the bone's two links
core::SkinnedMesh synthetic_skin(const core::Model& m) {
  core::SkinnedMesh s;
  s.name = "tubes";
  s.base_color = Eigen::Vector4f(0.9f, 0.6f, 0.4f, 1.0f);
  core::Data data(m);
  core::forward_kinematics(m, data, core::neutral_configuration(m));
  std::vector<int> bone_of_link(m.njoints, -1);
  auto bone = [&](int link) {
    if (bone_of_link[link] < 0) {
      bone_of_link[link] = static_cast<int>(s.bones.size());
      s.bones.push_back(link);
      s.inverse_bind.push_back(data.X_W[link].inverse());
    }
    return bone_of_link[link];
  };
  for (int i = 2; i < m.njoints; ++i) {
    const int p = m.parent[i];
    if (p < 1) continue;
    const Vector3 a = data.X_W[p].p, b = data.X_W[i].p;
    if ((b - a).norm() < 1e-6) continue;
    const Vector3 d = (b - a).normalized(), u = d.unitOrthogonal(), w = d.cross(u);
    const int base = static_cast<int>(s.positions.size());
    for (int ring = 0; ring < 3; ++ring) {
      const double f = ring / 2.0;
      for (int c = 0; c < 8; ++c) {
        const double ang = c * M_PI / 4;
        const Vector3 n = std::cos(ang) * u + std::sin(ang) * w;
        s.positions.push_back((a + f * (b - a) + 0.03 * n).cast<float>());
        s.normals.push_back(n.cast<float>());
        // three influences, one of them a duplicate of the parent, weights not yet normalized
        s.joints.push_back({bone(p), bone(i), bone(p), 0});
        s.weights.push_back({static_cast<float>(1 - f), static_cast<float>(f), 0.25f, 0.0f});
      }
    }
    for (int ring = 0; ring < 2; ++ring) {
      for (int c = 0; c < 8; ++c) {
        const int v00 = base + ring * 8 + c, v01 = base + ring * 8 + (c + 1) % 8;
        s.triangles.push_back({v00, v01, v00 + 8});
        s.triangles.push_back({v01, v01 + 8, v00 + 8});
      }
    }
  }
  return s;
}

TEST(GltfExport, SkinnedMeshAttributesAreValidAndSkinLikeOurModel) {
  const auto m = human();
  const core::Clip clip = synthetic_clip(*m, 60);
  const core::SkinnedMesh skin = synthetic_skin(*m);
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::parse_glb(io::write_glb(*m, &clip, &skin), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  expect_structure(*m, &clip, doc);
  expect_keys_match_fk(*m, clip, doc, kFkTolerance);
  const Json& j = doc.json;
  ASSERT_EQ(j["meshes"].size(), 1u);
  const Json& prim = j["meshes"][0]["primitives"][0];
  const Json& attr = prim["attributes"];
  EXPECT_EQ(j["accessors"][attr["JOINTS_0"].get<int>()]["componentType"], 5123);
  EXPECT_EQ(j["accessors"][attr["WEIGHTS_0"].get<int>()]["componentType"], 5126);
  const auto pos = gltf_test::read_accessor(doc, attr["POSITION"]);
  const auto nrm = gltf_test::read_accessor(doc, attr["NORMAL"]);
  const auto jnt = gltf_test::read_accessor(doc, attr["JOINTS_0"]);
  const auto wgt = gltf_test::read_accessor(doc, attr["WEIGHTS_0"]);
  const auto idx = gltf_test::read_accessor(doc, prim["indices"]);
  ASSERT_EQ(pos.size(), 3 * skin.positions.size());
  ASSERT_EQ(idx.size(), 3 * skin.triangles.size());
  const size_t njoints = j["skins"][0]["joints"].size();
  // the mesh node: a root with an identity transform
  int mesh_node = -1;
  for (size_t n = 0; n < j["nodes"].size(); ++n)
    if (j["nodes"][n].contains("mesh")) mesh_node = static_cast<int>(n);
  ASSERT_GE(mesh_node, 0);
  EXPECT_FALSE(j["nodes"][mesh_node].contains("translation"));
  EXPECT_FALSE(j["nodes"][mesh_node].contains("rotation"));
  EXPECT_EQ(j["nodes"][mesh_node]["skin"], 0);
  // base colour
  const Json& mat = j["materials"][prim["material"].get<int>()];
  EXPECT_NEAR(mat["pbrMetallicRoughness"]["baseColorFactor"][1].get<double>(), 0.6, 1e-6);

  // skin the mesh at every key with the file's data and compare with our model's skinning
  const auto worlds = gltf_test::world_matrices_at_keys(doc, 0);
  const auto ibm = gltf_test::read_accessor(doc, j["skins"][0]["inverseBindMatrices"]);
  core::Data data(*m);
  double worst = 0;
  for (int k = 0; k < clip.size(); k += 7) {
    core::forward_kinematics(*m, data, clip.frames[k]);
    for (size_t v = 0; v < skin.positions.size(); ++v) {
      double wsum = 0;
      std::set<int> used;
      Eigen::Vector4d p_file = Eigen::Vector4d::Zero();
      for (int c = 0; c < 4; ++c) {
        const double w = wgt[4 * v + c];
        ASSERT_GE(w, 0.0);
        wsum += w;
        if (w == 0) continue;
        const int sj = static_cast<int>(jnt[4 * v + c]);
        ASSERT_LT(static_cast<size_t>(sj), njoints);
        EXPECT_TRUE(used.insert(sj).second) << "vertex " << v << " repeats joint " << sj;
        Eigen::Matrix4d M;
        for (int e = 0; e < 16; ++e) M(e % 4, e / 4) = ibm[16 * sj + e];
        const int node = j["skins"][0]["joints"][sj];
        p_file += w * worlds[k][node] * M *
                  Eigen::Vector4d(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2], 1);
      }
      // the validator's rule: |sum - 1| <= 2e-7 * (number of non-zero weights)
      ASSERT_LE(std::abs(wsum - 1.0), 2e-7 * static_cast<double>(used.size())) << "vertex " << v;
      ASSERT_NEAR(Eigen::Vector3d(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]).norm(), 1.0, 1e-6);
      // our skinning: normalized weights with the duplicate merged
      const auto& jw = skin.joints[v];
      const auto& ww = skin.weights[v];
      const double total = ww[0] + ww[1] + ww[2] + ww[3];
      Vector3 p_ours = Vector3::Zero();
      for (int c = 0; c < 4; ++c) {
        if (ww[c] == 0) continue;
        const int link = skin.bones[jw[c]];
        p_ours += (ww[c] / total) *
                  (data.X_W[link] * (skin.inverse_bind[jw[c]] * skin.positions[v].cast<double>()));
      }
      worst = std::max(worst, (p_file.head<3>() - p_ours).norm());
    }
  }
  EXPECT_LE(worst, 1e-5);
  std::printf("  skinned vertices, file vs our skinning: max distance %.3g m\n", worst);
}

// Each part of a mesh is a primitive with its own material; a textured part's image is stored in
// the buffer as given and sampled with TEXCOORD_0 in glTF's convention (v from the top); a bad
// part is refused naming it; a mesh without triangles is written as its points.
TEST(GltfExport, PartsArePrimitivesWithTheirMaterialsAndTextures) {
  const auto m = human();
  core::SkinnedMesh skin = synthetic_skin(*m);
  const int nt = static_cast<int>(skin.triangles.size());
  for (std::size_t v = 0; v < skin.positions.size(); ++v) {
    skin.uvs.emplace_back(0.001f * static_cast<float>(v % 1000), 0.25f);
  }
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + "not a real image";
  skin.textures.push_back({"image/png", png});
  skin.parts = {{0, 10, Eigen::Vector4f(0.1f, 0.2f, 0.3f, 1.0f), -1},
                {10, nt - 10, Eigen::Vector4f(1.0f, 1.0f, 1.0f, 1.0f), 0}};
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::parse_glb(io::write_glb(*m, nullptr, &skin), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  gltf_test::check_layout(doc, errors);
  const Json& j = doc.json;
  const Json& prims = j["meshes"][0]["primitives"];
  ASSERT_EQ(prims.size(), 2u);
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(gltf_test::read_accessor(doc, prims[k]["indices"]).size(),
              3u * static_cast<std::size_t>(skin.parts[k].triangle_count));
    const Json& pbr = j["materials"][prims[k]["material"].get<int>()]["pbrMetallicRoughness"];
    // glTF's default factor (1, 1, 1, 1) may be left out
    const Json factor = pbr.value("baseColorFactor", Json::array({1.0, 1.0, 1.0, 1.0}));
    EXPECT_NEAR(factor[2].get<double>(), skin.parts[k].base_color[2], 1e-6);
    EXPECT_EQ(pbr.contains("baseColorTexture"), k == 1);
  }
  const Json& pbr1 = j["materials"][prims[1]["material"].get<int>()]["pbrMetallicRoughness"];
  const Json& image =
      j["images"][j["textures"][pbr1["baseColorTexture"]["index"].get<int>()]["source"].get<int>()];
  EXPECT_EQ(image["mimeType"], "image/png");
  const Json& view = j["bufferViews"][image["bufferView"].get<int>()];
  const std::size_t at = view.value("byteOffset", 0);
  EXPECT_EQ(std::string(doc.bin.begin() + at, doc.bin.begin() + at + view["byteLength"].get<int>()),
            png);
  const auto uv = gltf_test::read_accessor(doc, prims[0]["attributes"]["TEXCOORD_0"]);
  ASSERT_EQ(uv.size(), 2 * skin.uvs.size());
  EXPECT_NEAR(uv[2 * 7], skin.uvs[7].x(), 1e-7);
  EXPECT_NEAR(uv[2 * 7 + 1], 0.75, 1e-7);  // 1 − v

  core::SkinnedMesh bad = skin;
  bad.parts[1].texture = 4;
  try {
    io::write_glb(*m, nullptr, &bad);
    ADD_FAILURE() << "a part naming a texture that does not exist was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("part 1: texture 4 does not exist"), std::string::npos)
        << e.what();
  }

  core::SkinnedMesh points = synthetic_skin(*m);
  points.triangles.clear();
  const gltf_test::Document dots =
      gltf_test::parse_glb(io::write_glb(*m, nullptr, &points), errors);
  ASSERT_EQ(dots.json["meshes"][0]["primitives"].size(), 1u);
  EXPECT_EQ(dots.json["meshes"][0]["primitives"][0]["mode"], 0);  // POINTS
  EXPECT_FALSE(dots.json["meshes"][0]["primitives"][0].contains("indices"));
}

TEST(GltfExport, StickFigureBoxesAreRigidlySkinnedToTheirLinks) {
  const auto m = human();
  io::GltfExportOptions o;
  o.stick_figure = true;
  o.stick_radius = 0.01;
  std::vector<std::string> errors;
  const gltf_test::Document doc =
      gltf_test::parse_glb(io::write_glb(*m, nullptr, nullptr, o), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  expect_structure(*m, nullptr, doc);
  const Json& j = doc.json;
  ASSERT_EQ(j["meshes"].size(), 1u);
  EXPECT_EQ(j["meshes"][0]["name"], "stick_figure");
  const Json& attr = j["meshes"][0]["primitives"][0]["attributes"];
  const auto pos = gltf_test::read_accessor(doc, attr["POSITION"]);
  const auto jnt = gltf_test::read_accessor(doc, attr["JOINTS_0"]);
  const auto wgt = gltf_test::read_accessor(doc, attr["WEIGHTS_0"]);
  core::Data data(*m);
  core::forward_kinematics(*m, data, core::neutral_configuration(*m));
  const std::vector<int> node = node_of_link(*m, j);
  std::vector<int> vertices_of_link(m->njoints, 0);
  // every vertex: weight 1 on one joint, within the box around a segment from its link's origin
  for (size_t v = 0; v < pos.size() / 3; ++v) {
    ASSERT_EQ(wgt[4 * v], 1.0);
    const int n = j["skins"][0]["joints"][static_cast<int>(jnt[4 * v])];
    int link = -1;
    for (int i = 1; i < m->njoints; ++i)
      if (node[i] == n) link = i;
    ASSERT_GT(link, 0);
    ++vertices_of_link[link];
    const Vector3 p_L =
        data.X_W[link].inverse_apply(Vector3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
    double best = p_L.norm();
    for (int c = link + 1; c < m->subtree_end[link]; ++c) {
      if (m->parent[c] != link) continue;
      const Vector3 b = m->X_PJ[c].p;
      const double s = std::clamp(p_L.dot(b) / std::max(b.squaredNorm(), 1e-18), 0.0, 1.0);
      best = std::min(best, (p_L - s * b).norm());
    }
    EXPECT_LE(best, 1.5 * 0.01 * std::sqrt(3.0) + 1e-6);
  }
  for (int i = 1; i < m->njoints; ++i) EXPECT_GE(vertices_of_link[i], 24) << m->link_name[i];
}

TEST(GltfExport, NodeNamesAreSanitizedUniqueAndKeepTheOriginalInExtras) {
  core::ModelBuilder b("names");
  core::LinkSpec root = fixtures::box_link("nodes[21]", "", 1.0, Vector3(0.1, 0.1, 0.1));
  root.joint.type = JointType::kFree;
  b.add_link(root);
  core::LinkSpec c = fixtures::box_link("nodes_21_", "nodes[21]", 1.0, Vector3(0.1, 0.1, 0.1));
  c.joint.type = JointType::kSpherical;
  c.joint.X_PJ.p = Vector3(0, 0.3, 0);
  b.add_link(c);
  core::LinkSpec d = fixtures::box_link("Bone.006", "nodes_21_", 1.0, Vector3(0.1, 0.1, 0.1));
  d.joint.type = JointType::kRevolute;
  d.joint.X_PJ.p = Vector3(0, 0.3, 0);
  b.add_link(d);
  const auto m = b.finalize();
  std::vector<std::string> errors;
  const auto doc = gltf_test::parse_gltf(io::write_gltf(*m, nullptr, nullptr), errors);
  std::set<std::string> names;
  for (const Json& n : doc.json["nodes"]) {
    const std::string s = n["name"];
    EXPECT_TRUE(names.insert(s).second) << s;
    for (char ch : s) EXPECT_TRUE(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_') << s;
  }
  const std::vector<int> node = node_of_link(*m, doc.json);
  for (int i = 1; i < m->njoints; ++i) EXPECT_GE(node[i], 0) << m->link_name[i];
}

TEST(GltfExport, RejectsInputThatDoesNotFitTheModel) {
  const auto m = human();
  core::Clip clip = synthetic_clip(*m, 5);
  clip.frames[3].conservativeResize(m->nq - 1);
  try {
    io::write_glb(*m, &clip, nullptr);
    FAIL() << "a frame of the wrong size was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 3"), std::string::npos) << e.what();
  }
  core::Clip nan_clip = synthetic_clip(*m, 5);
  nan_clip.frames[2][0] = std::nan("");
  EXPECT_THROW(io::write_gltf(*m, &nan_clip, nullptr), std::invalid_argument);

  core::SkinnedMesh skin = synthetic_skin(*m);
  skin.joints[17][1] = 999;
  try {
    io::write_glb(*m, nullptr, &skin);
    FAIL() << "a joint index outside the bones was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 17"), std::string::npos) << e.what();
  }
  skin = synthetic_skin(*m);
  skin.triangles[4][2] = -1;
  EXPECT_THROW(io::write_glb(*m, nullptr, &skin), std::invalid_argument);
  skin = synthetic_skin(*m);
  skin.bones[0] = m->njoints;
  EXPECT_THROW(io::write_glb(*m, nullptr, &skin), std::invalid_argument);

  core::Clip tiny = synthetic_clip(*m, 3);
  tiny.frame_time = 1e-300;
  EXPECT_THROW(io::write_glb(*m, &tiny, nullptr), std::invalid_argument);
}

TEST(GltfExport, SaveChoosesTheFormatByExtensionAndWritesAtomically) {
  const auto m = human();
  const core::Clip clip = synthetic_clip(*m, 20);
  gltf_test::TempDir dir;
  io::save_gltf_file(dir.path("a.glb"), *m, &clip, nullptr, {});
  io::save_gltf_file(dir.path("b.GLTF"), *m, &clip, nullptr, {});
  const auto glb = gltf_test::read_bytes(dir.path("a.glb"));
  ASSERT_GE(glb.size(), 12u);
  EXPECT_EQ(std::string(glb.begin(), glb.begin() + 4), "glTF");
  EXPECT_EQ(glb, io::write_glb(*m, &clip, nullptr));
  const auto text = gltf_test::read_bytes(dir.path("b.GLTF"));
  EXPECT_EQ(std::string(text.begin(), text.end()), io::write_gltf(*m, &clip, nullptr));
  try {
    io::save_gltf_file(dir.path("c.obj"), *m, &clip, nullptr, {});
    FAIL() << "an .obj path was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("c.obj"), std::string::npos) << e.what();
  }
  EXPECT_THROW(io::save_gltf_file(dir.path("missing/d.glb"), *m, &clip, nullptr, {}),
               std::system_error);
  // nothing but the two outputs: no temporary file left behind
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.dir())) {
    ++files;
    EXPECT_TRUE(e.path().filename() == "a.glb" || e.path().filename() == "b.GLTF") << e.path();
  }
  EXPECT_EQ(files, 2);
}

// ---------------------------------------------------------------------------------------------
// independent readers

struct Written {
  std::string label;
  std::string path;
};

// everything we write, as .gltf and .glb: skeleton only, with a clip, with the stick figure,
// with the shape mesh, with a skinned mesh, and the branching tree with fixed and prismatic
// joints
std::vector<Written> write_variants(const gltf_test::TempDir& dir) {
  const auto m = human();
  const auto tree = fixtures::branching_tree();
  static const core::Clip clip = synthetic_clip(*m, 400);
  core::Clip tree_clip;
  for (int k = 0; k < 30; ++k) tree_clip.frames.push_back(core::random_configuration(*tree, 7 + k));
  const core::SkinnedMesh skin = synthetic_skin(*m);
  io::GltfExportOptions stick;
  stick.stick_figure = true;
  io::GltfExportOptions shapes;
  shapes.shape_mesh = true;
  std::vector<Written> out;
  for (const char* ext : {".gltf", ".glb"}) {
    auto add = [&](const std::string& label, const core::Model& model, const core::Clip* c,
                   const core::SkinnedMesh* s, const io::GltfExportOptions& o) {
      const std::string path = dir.path(label + ext);
      io::save_gltf_file(path, model, c, s, o);
      out.push_back({label + ext, path});
    };
    add("human48_skeleton", *m, nullptr, nullptr, {});
    add("human48_clip", *m, &clip, nullptr, {});
    add("human48_stick", *m, &clip, nullptr, stick);
    add("human48_shapes", *m, &clip, nullptr, shapes);
    add("human48_skinned", *m, &clip, &skin, stick);
    add("tree_clip", *tree, &tree_clip, nullptr, {});
  }
  return out;
}

TEST(GltfExport, KhronosValidatorReportsNoErrorsAndOnlyAllowedIssues) {
  const std::string why = gltf_test::node_unavailable();
  if (!why.empty()) GTEST_SKIP() << "Khronos validator check skipped: " << why;
  gltf_test::TempDir dir;
  for (const Written& w : write_variants(dir)) {
    const Json r = gltf_test::validate(w.path);
    std::printf("  validator %-24s errors %d warnings %d infos %d hints %d", w.label.c_str(),
                r["errors"].get<int>(), r["warnings"].get<int>(), r["infos"].get<int>(),
                r["hints"].get<int>());
    std::set<std::string> codes;
    for (const Json& msg : r["messages"]) codes.insert(msg["code"].get<std::string>());
    for (const auto& c : codes) std::printf(" %s", c.c_str());
    std::printf("\n");
    EXPECT_EQ(r["errors"], 0) << w.label << ": " << r.dump();
    for (const Json& msg : r["messages"]) {
      EXPECT_EQ(kAllowedIssues.count(msg["code"]), 1u)
          << w.label << ": " << msg["code"] << " at " << msg["pointer"] << ": " << msg["message"];
    }
  }
}

TEST(GltfExport, ThreeJsGltfLoaderSeesOurForwardKinematics) {
  const std::string why = gltf_test::node_unavailable();
  if (!why.empty()) GTEST_SKIP() << "three.js check skipped: " << why;
  const auto m = human();
  const core::Clip clip = synthetic_clip(*m, 400);
  gltf_test::TempDir dir;
  io::GltfExportOptions stick, shapes;
  stick.stick_figure = true;
  shapes.shape_mesh = true;
  const std::map<std::string, io::GltfExportOptions> files = {{"h.gltf", {}},
                                                              {"h.glb", {}},
                                                              {"h_stick.glb", stick},
                                                              {"h_shapes.gltf", shapes},
                                                              {"h_shapes.glb", shapes}};
  for (const auto& [name, options] : files) {
    const std::string path = dir.path(name);
    io::save_gltf_file(path, *m, &clip, nullptr, options);
    const Json r = gltf_test::three_read(path, "keys");
    ASSERT_EQ(r["animations"], 1);
    // one SkinnedMesh with a material per mesh written, bound to every link
    const bool mesh = options.stick_figure || options.shape_mesh;
    ASSERT_EQ(r["skinned_meshes"].size(), mesh ? 1u : 0u) << name;
    for (const Json& sm : r["skinned_meshes"]) {
      EXPECT_GT(sm["vertices"].get<int>(), 0) << name;
      EXPECT_TRUE(sm["material"].get<bool>()) << name;
      EXPECT_EQ(sm["bones"].get<int>(), m->nlinks()) << name;
    }
    // three.js made every link a Bone (the skin lists them all)
    EXPECT_EQ(static_cast<int>(r["bones"].size()), m->nlinks()) << name;
    ASSERT_EQ(static_cast<int>(r["frames"].size()), clip.size());
    std::vector<std::string> errors;
    const std::vector<int> node = node_of_link(*m, gltf_test::load(path, errors).json);
    core::Data data(*m);
    double worst_p = 0, worst_r = 0;
    for (int k = 0; k < clip.size(); ++k) {
      core::forward_kinematics(*m, data, clip.frames[k]);
      for (int i = 1; i < m->njoints; ++i) {
        const Json& f = r["frames"][k][node[i]];
        ASSERT_TRUE(f.is_array()) << m->link_name[i];
        const Vector3 p(f[0].get<double>(), f[1].get<double>(), f[2].get<double>());
        const Quaternion q(f[6].get<double>(), f[3].get<double>(), f[4].get<double>(),
                           f[5].get<double>());
        worst_p = std::max(worst_p, (p - data.X_W[i].p).norm());
        worst_r = std::max(worst_r, max_abs(q.toRotationMatrix() - data.X_W[i].R));
      }
    }
    std::printf("  three.js %-14s %d frames: max position error %.3g m, rotation %.3g\n",
                name.c_str(), clip.size(), worst_p, worst_r);
    EXPECT_LE(worst_p, kThreeTolerance) << name;
    EXPECT_LE(worst_r, kThreeTolerance) << name;
  }
}

// "Nodes:  22" style lines of `assimp info`
int info_count(const std::string& out, const std::string& key) {
  const size_t at = out.find(key);
  if (at == std::string::npos) return -1;
  return std::atoi(out.c_str() + at + key.size());
}

TEST(GltfExport, AssimpCliReadsOurGltfAndGlb) {
  if (gltf_test::run("command -v assimp >/dev/null 2>&1").status != 0) {
    GTEST_SKIP() << "assimp CLI check skipped: `assimp` (Debian assimp-utils) is not on PATH";
  }
  const auto m = human();
  gltf_test::TempDir dir;
  int animated = 0;
  for (int i = 1; i < m->njoints; ++i) animated += m->joint_type[i] != JointType::kFixed;
  for (const Written& w : write_variants(dir)) {
    if (w.label.rfind("human48", 0) != 0) continue;
    // skeleton-only files need the raw import: assimp's default post-processing drops the
    // materials no mesh uses and then refuses a scene without any ("No materials remaining")
    const bool has_mesh = w.label.find("stick") != std::string::npos ||
                          w.label.find("shapes") != std::string::npos ||
                          w.label.find("skinned") != std::string::npos;
    const gltf_test::CommandResult r =
        gltf_test::run("assimp info " + gltf_test::quote(w.path) + (has_mesh ? "" : " -r"), true);
    ASSERT_EQ(r.status, 0) << w.label << "\n" << r.out;
    EXPECT_NE(r.out.find("Importing file ...                   OK"), std::string::npos) << r.out;
    // nodes: the links, the mesh nodes, and the root assimp adds above several scene roots;
    // bones: assimp makes one per skin joint for each skinned mesh
    const int meshes = w.label.find("skinned") != std::string::npos ? 2 : has_mesh ? 1 : 0;
    EXPECT_EQ(info_count(r.out, "Nodes:"), m->nlinks() + meshes + (meshes > 0 ? 1 : 0))
        << w.label << "\n"
        << r.out;
    EXPECT_EQ(info_count(r.out, "Bones:"), meshes * m->nlinks()) << w.label;
    const bool has_clip = w.label.find("skeleton") == std::string::npos;
    EXPECT_EQ(info_count(r.out, "Animation Channels:"), has_clip ? animated : 0) << w.label;
    EXPECT_EQ(info_count(r.out, "Meshes:"), meshes) << w.label;
    std::printf("  assimp info %-24s OK: nodes %d, meshes %d, bones %d, animation channels %d\n",
                w.label.c_str(), info_count(r.out, "Nodes:"), info_count(r.out, "Meshes:"),
                info_count(r.out, "Bones:"), info_count(r.out, "Animation Channels:"));
  }
}

}  // namespace
