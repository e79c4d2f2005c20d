// Tests for the shape mesh of io/gltf.hpp (GltfExportOptions::shape_mesh): the bundled human48
// exported with its shapes, read back by our own minimal reader (tests/io/gltf_reader.hpp): one
// mesh with a material, every vertex rigidly skinned to the link whose shape it lies on, at the
// bind pose; links without shapes get stick boxes; a model without shapes the stick figure; and
// the file imported again through assimp. The Khronos validator, three.js and `assimp info` read
// the same export in gltf_test.cpp (the human48_shapes variants).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "core/model_builder.hpp"
#include "io/assimp_import.hpp"
#include "io/bundled_characters.hpp"
#include "io/gltf.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/io/gltf_reader.hpp"

namespace {

using core::Geometry;
using core::Vector3;
using gltf_test::Json;

// float positions a few metres from the origin, skinned in double: metres
constexpr double kPositionTolerance = 1e-5;

io::GltfExportOptions with_shapes() {
  io::GltfExportOptions o;
  o.shape_mesh = true;
  return o;
}

// the shapes a link is drawn with, by the rule of docs/formats.md: its visual shapes when one is
// a primitive, else its collision shapes when one is, else none
std::vector<Geometry> drawn_shapes(const core::Model& m, int link) {
  auto primitive = [](const std::vector<Geometry>& s) {
    return std::any_of(s.begin(), s.end(),
                       [](const Geometry& g) { return g.shape != Geometry::Shape::kMesh; });
  };
  if (primitive(m.visual[link])) return m.visual[link];
  if (primitive(m.collision[link])) return m.collision[link];
  return {};
}

// signed distance of p (shape frame) to a primitive shape: < 0 inside, > 0 outside
double signed_distance(const Geometry& g, const Vector3& p) {
  switch (g.shape) {
    case Geometry::Shape::kSphere:
      return p.norm() - g.radius;
    case Geometry::Shape::kCapsule: {
      const double z = std::clamp(p.z(), -0.5 * g.length, 0.5 * g.length);
      return (p - Vector3(0, 0, z)).norm() - g.radius;
    }
    case Geometry::Shape::kCylinder: {
      const Eigen::Vector2d d(p.head<2>().norm() - g.radius, std::abs(p.z()) - 0.5 * g.length);
      return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
    }
    case Geometry::Shape::kBox: {
      const Vector3 q = p.cwiseAbs() - 0.5 * g.size;
      return std::min(q.maxCoeff(), 0.0) + q.cwiseMax(0.0).norm();
    }
    case Geometry::Shape::kMesh:
      break;
  }
  return std::numeric_limits<double>::infinity();
}

// The shape mesh as the file holds it: positions and normals (bind pose, world) and the link of
// each vertex's joint, checked on the way: one mesh with one primitive and a material, weights
// (1, 0, 0, 0), and the positions skinned by the file's own nodes and inverse bind matrices at
// the bind pose equal to the stored ones.
struct ShapeMesh {
  std::vector<Vector3> pos, nrm;
  std::vector<int> link;
};

// link index of every skin joint, by node name (or extras.link when the name was sanitized)
std::vector<int> link_of_joint(const core::Model& m, const Json& j) {
  std::vector<int> out;
  for (const Json& n : j["skins"][0]["joints"]) {
    const Json& node = j["nodes"][n.get<int>()];
    std::string name = node.value("name", "");
    if (node.contains("extras") && node["extras"].contains("link")) name = node["extras"]["link"];
    out.push_back(m.link_index(name));
  }
  return out;
}

void expect_one_mesh_with_a_material(const Json& j, const std::string& name) {
  ASSERT_EQ(j["meshes"].size(), 1u);
  EXPECT_EQ(j["meshes"][0]["name"], name);
  ASSERT_EQ(j["meshes"][0]["primitives"].size(), 1u);
  const Json& prim = j["meshes"][0]["primitives"][0];
  ASSERT_TRUE(prim.contains("material"));
  ASSERT_EQ(j["materials"].size(), 1u);
  const Json& color =
      j["materials"][prim["material"].get<int>()]["pbrMetallicRoughness"]["baseColorFactor"];
  ASSERT_EQ(color.size(), 4u);
  for (const Json& c : color) EXPECT_TRUE(c.get<double>() >= 0 && c.get<double>() <= 1);
  for (const char* a : {"POSITION", "NORMAL", "JOINTS_0", "WEIGHTS_0"})
    EXPECT_TRUE(prim["attributes"].contains(a)) << a;
}

ShapeMesh read_shape_mesh(const core::Model& m, const gltf_test::Document& doc) {
  const Json& j = doc.json;
  const Json& attr = j["meshes"][0]["primitives"][0]["attributes"];
  const auto pos = gltf_test::read_accessor(doc, attr["POSITION"]);
  const auto nrm = gltf_test::read_accessor(doc, attr["NORMAL"]);
  const auto jnt = gltf_test::read_accessor(doc, attr["JOINTS_0"]);
  const auto wgt = gltf_test::read_accessor(doc, attr["WEIGHTS_0"]);
  const auto ibm = gltf_test::read_accessor(doc, j["skins"][0]["inverseBindMatrices"]);
  const auto worlds = gltf_test::world_matrices_at_keys(doc, 0);  // no animation: the bind pose
  const std::vector<int> links = link_of_joint(m, j);
  ShapeMesh out;
  double worst = 0;
  for (size_t v = 0; v < pos.size() / 3; ++v) {
    EXPECT_EQ(wgt[4 * v], 1.0) << "vertex " << v;
    const int sj = static_cast<int>(jnt[4 * v]);
    out.pos.emplace_back(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
    out.nrm.emplace_back(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]);
    out.link.push_back(links.at(sj));
    Eigen::Matrix4d M;
    for (int e = 0; e < 16; ++e) M(e % 4, e / 4) = ibm[16 * sj + e];
    const int node = j["skins"][0]["joints"][sj];
    const Eigen::Vector4d skinned = worlds[0][node] * M * out.pos.back().homogeneous();
    worst = std::max(worst, (skinned.head<3>() - out.pos.back()).norm());
  }
  EXPECT_LE(worst, kPositionTolerance) << "skinned at the bind pose vs stored positions";
  return out;
}

// Every vertex of a link with shapes lies on one of them (within kPositionTolerance) with an
// outward unit normal, and every shape gets vertices. Counts the vertices of each link.
void expect_vertices_on_their_links_shapes(const core::Model& m,
                                           const ShapeMesh& s,
                                           std::vector<int>& per_link) {
  core::Data data(m);
  core::forward_kinematics(m, data, core::neutral_configuration(m));
  per_link.assign(m.njoints, 0);
  std::vector<std::vector<int>> per_shape(m.njoints);
  double worst = 0;
  for (size_t v = 0; v < s.pos.size(); ++v) {
    const int i = s.link[v];
    ++per_link.at(i);
    const std::vector<Geometry> shapes = drawn_shapes(m, i);
    if (shapes.empty()) continue;
    per_shape[i].resize(shapes.size());
    int best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < shapes.size(); ++k) {
      const core::Transform X_WS = data.X_W[i] * shapes[k].X_LinkShape;
      const double d = std::abs(signed_distance(shapes[k], X_WS.inverse_apply(s.pos[v])));
      if (d < best_d) best_d = d, best = static_cast<int>(k);
    }
    worst = std::max(worst, best_d);
    ASSERT_LE(best_d, kPositionTolerance)
        << "vertex " << v << " is off the shapes of link " << m.link_name[i];
    ++per_shape[i][best];
    ASSERT_NEAR(s.nrm[v].norm(), 1.0, 1e-6) << "vertex " << v;
    const core::Transform X_WS = data.X_W[i] * shapes[best].X_LinkShape;
    const double out =
        signed_distance(shapes[best], X_WS.inverse_apply(s.pos[v] + 1e-3 * s.nrm[v]));
    ASSERT_GT(out, 0.9e-3) << "vertex " << v << " of link " << m.link_name[i]
                           << ": the normal does not point out of its shape";
  }
  for (int i = 1; i < m.njoints; ++i) {
    for (size_t k = 0; k < per_shape[i].size(); ++k)
      EXPECT_GT(per_shape[i][k], 0) << m.link_name[i] << " shape " << k;
  }
  std::printf("  shape mesh: %zu vertices, max distance to their link's shapes %.3g m\n",
              s.pos.size(), worst);
}

// every triangle has an area (importers such as assimp turn the others into lines or points in a
// mesh of their own) and every vertex is used
void expect_triangles_with_area(const gltf_test::Document& doc, const ShapeMesh& s) {
  const auto idx =
      gltf_test::read_accessor(doc, doc.json["meshes"][0]["primitives"][0]["indices"].get<int>());
  std::vector<char> used(s.pos.size(), 0);
  for (size_t t = 0; t + 2 < idx.size(); t += 3) {
    const Eigen::Vector3f a = s.pos.at(idx[t]).cast<float>(),
                          b = s.pos.at(idx[t + 1]).cast<float>(),
                          c = s.pos.at(idx[t + 2]).cast<float>();
    ASSERT_GT((b - a).cross(c - a).norm(), 0.0f) << "triangle " << t / 3;
    for (size_t k = t; k < t + 3; ++k) used[static_cast<size_t>(idx[k])] = 1;
  }
  EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0) << "vertices without a triangle";
}

TEST(GltfShapeMesh, Human48HasOneMeshWithAMaterialOnItsLinksShapesAtTheBindPose) {
  const auto m = io::load_character("human48").model;
  for (const bool binary : {false, true}) {
    std::vector<std::string> errors;
    const gltf_test::Document doc =
        binary ? gltf_test::parse_glb(io::write_glb(*m, nullptr, nullptr, with_shapes()), errors)
               : gltf_test::parse_gltf(io::write_gltf(*m, nullptr, nullptr, with_shapes()), errors);
    gltf_test::check_layout(doc, errors);
    for (const auto& e : errors) ADD_FAILURE() << e;
    expect_one_mesh_with_a_material(doc.json, "shapes");
    const ShapeMesh s = read_shape_mesh(*m, doc);
    ASSERT_GT(s.pos.size(), 0u);
    expect_triangles_with_area(doc, s);
    std::vector<int> per_link;
    expect_vertices_on_their_links_shapes(*m, s, per_link);
    for (int i = 1; i < m->njoints; ++i) EXPECT_GT(per_link[i], 0) << m->link_name[i];
    std::printf(
        "  human48 %s: %zu vertices, %zu triangles, %d links\n", binary ? "glb" : "gltf",
        s.pos.size(),
        doc.json["accessors"][doc.json["meshes"][0]["primitives"][0]["indices"].get<int>()]["count"]
                .get<size_t>() /
            3,
        m->nlinks());
  }
}

// root: a visual box over a collision capsule (the visual wins); arm: a collision sphere; hand: a
// visual cylinder; finger: no shape (stick boxes); tip: a mesh shape only (stick boxes)
std::shared_ptr<const core::Model> mixed_shapes() {
  core::ModelBuilder b("mixed");
  auto shape = [](Geometry::Shape kind, const Vector3& at) {
    Geometry g;
    g.shape = kind;
    g.X_LinkShape.p = at;
    g.radius = 0.04;
    g.length = 0.1;
    g.size = Vector3(0.2, 0.1, 0.3);
    g.mesh = "part.obj";
    return g;
  };
  auto link = [&](const char* name, const char* parent, double y) {
    core::LinkSpec l = fixtures::box_link(name, parent, 1.0, Vector3(0.05, 0.05, 0.05));
    l.joint.type = *parent == '\0' ? core::JointType::kFree : core::JointType::kSpherical;
    l.joint.X_PJ.p = Vector3(0, y, 0);
    return l;
  };
  core::LinkSpec root = link("root", "", 1.0);
  root.visual = {shape(Geometry::Shape::kBox, Vector3(0, 0.1, 0))};
  root.collision = {shape(Geometry::Shape::kCapsule, Vector3::Zero())};
  core::LinkSpec arm = link("arm", "root", 0.3);
  arm.collision = {shape(Geometry::Shape::kSphere, Vector3(0, 0.1, 0))};
  core::LinkSpec hand = link("hand", "arm", 0.25);
  hand.visual = {shape(Geometry::Shape::kCylinder, Vector3(0, 0.05, 0))};
  core::LinkSpec finger = link("finger", "hand", 0.2);
  core::LinkSpec tip = link("tip", "finger", 0.1);
  tip.visual = {shape(Geometry::Shape::kMesh, Vector3::Zero())};
  for (const auto& l : {root, arm, hand, finger, tip}) b.add_link(l);
  return b.finalize();
}

TEST(GltfShapeMesh, LinksWithoutShapesGetStickBoxesAndAModelWithoutShapesTheStickFigure) {
  const auto m = mixed_shapes();
  io::GltfExportOptions o = with_shapes();
  o.stick_radius = 0.01;
  std::vector<std::string> errors;
  const gltf_test::Document doc =
      gltf_test::parse_glb(io::write_glb(*m, nullptr, nullptr, o), errors);
  for (const auto& e : errors) ADD_FAILURE() << e;
  expect_one_mesh_with_a_material(doc.json, "shapes");
  const ShapeMesh s = read_shape_mesh(*m, doc);
  std::vector<int> per_link;
  expect_vertices_on_their_links_shapes(*m, s, per_link);
  // the shapeless links: a cube on the origin and a box to the child, 6 faces × 4 vertices each,
  // within the box half widths of the bone from the link's origin to the child's
  core::Data data(*m);
  core::forward_kinematics(*m, data, core::neutral_configuration(*m));
  for (const char* name : {"finger", "tip"}) {
    const int i = m->link_index(name);
    const bool leaf = m->subtree_end[i] == i + 1;
    EXPECT_EQ(per_link[i], leaf ? 24 : 48) << name;
    const Vector3 child = leaf ? Vector3::Zero() : Vector3(m->X_PJ[i + 1].p);
    for (size_t v = 0; v < s.pos.size(); ++v) {
      if (s.link[v] != i) continue;
      const Vector3 p_L = data.X_W[i].inverse_apply(s.pos[v]);
      const double t = child.squaredNorm() > 0
                           ? std::clamp(p_L.dot(child) / child.squaredNorm(), 0.0, 1.0)
                           : 0.0;
      EXPECT_LE((p_L - t * child).norm(), 1.5 * 0.01 * std::sqrt(3.0) + 1e-6) << name;
    }
  }
  // no shape anywhere: the stick figure
  const auto tree = fixtures::branching_tree();
  const gltf_test::Document sticks =
      gltf_test::parse_glb(io::write_glb(*tree, nullptr, nullptr, with_shapes()), errors);
  expect_one_mesh_with_a_material(sticks.json, "stick_figure");
  // the option's radius is checked as the stick figure's is
  o.stick_radius = 0;
  EXPECT_THROW(io::write_glb(*m, nullptr, nullptr, o), std::invalid_argument);
}

TEST(GltfShapeMesh, AssimpImportsTheExportAsASkinnedCharacterOfEveryLink) {
  const auto m = io::load_character("human48").model;
  gltf_test::TempDir dir;
  const std::string path = dir.path("human48_shapes.glb");
  io::save_gltf_file(path, *m, nullptr, nullptr, with_shapes());
  const io::SkinnedImport imp = io::import_skinned_file(path);
  EXPECT_EQ(imp.model->nlinks(), m->nlinks());
  EXPECT_EQ(static_cast<int>(imp.mesh.bones.size()), m->nlinks());
  ASSERT_FALSE(imp.mesh.positions.empty());
  // the same surface: the bounds of the imported vertices equal those of the written ones
  std::vector<std::string> errors;
  const gltf_test::Document doc = gltf_test::load(path, errors);
  const Json& position =
      doc.json["accessors"]
              [doc.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
  Eigen::Vector3f lo = imp.mesh.positions[0], hi = lo;
  for (const Eigen::Vector3f& p : imp.mesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(lo[c], position["min"][c].get<double>(), kPositionTolerance);
    EXPECT_NEAR(hi[c], position["max"][c].get<double>(), kPositionTolerance);
  }
  std::printf("  assimp import: %d links, %zu vertices, %zu bones\n", imp.model->nlinks(),
              imp.mesh.positions.size(), imp.mesh.bones.size());
}

}  // namespace
