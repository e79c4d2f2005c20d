// Tests for the BVH import of non-root joints with position channels (io/bvh_import.hpp): a
// translation constant over the frames (exactly or up to noise) makes a rotational joint at that
// offset, a moving one stays free; world poses are the file's, the export reads back to the same
// poses, and `pindrag info` (run as the executable) reports the choice.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/run_pindrag.hpp"
#include "tests/io/gltf_reader.hpp"

namespace {

using core::JointType;
using core::Transform;
using core::Vector3;
using io::BvhDocument;
using io::BvhImport;
using io::BvhImportOptions;

// One joint of the synthetic figure (centimetres).
struct J {
  std::string name;
  int parent;
  Vector3 offset;       // OFFSET
  Vector3 position;     // the position channels' constant value (Prop: their mean)
  bool moving = false;  // Prop: its position channels move by up to `amplitude`
};

// A figure of about 170 cm where every joint has 6 channels (positions first, then ZXY): the
// position channels of the non-root joints repeat their OFFSET plus uniform noise in
// [-noise, noise] (file units), except that Spine's carry another constant than its OFFSET (the
// values replace it) and Prop's move by `amplitude`. Rotations change every frame.
const std::vector<J>& figure() {
  static const std::vector<J> js = {
      {"Hips", -1, {0, 95, 0}, {0, 95, 0}},
      {"Spine", 0, {0, 0, 0}, {0, 10, -1}},  // OFFSET zero, the channels hold the bone
      {"Chest", 1, {0, 12, 0.5}, {0, 12, 0.5}},
      {"Neck", 2, {0, 25, 0}, {0, 25, 0}},
      {"Head", 3, {0, 10, 1}, {0, 10, 1}},
      {"LeftArm", 2, {15, 20, 0}, {15, 20, 0}},
      {"LeftForeArm", 5, {28, 0, 0}, {28, 0, 0}},
      {"LeftHand", 6, {25, 0, 0}, {25, 0, 0}},
      {"Prop", 7, {5, 2, 0}, {5, 2, 0}, true},
      {"LeftUpLeg", 0, {9, -5, 0}, {9, -5, 0}},
      {"LeftLeg", 9, {0, -42, 1}, {0, -42, 1}},
      {"LeftFoot", 10, {0, -43, -2}, {0, -43, -2}},
  };
  return js;
}

std::string figure_bvh(int frames, double noise, double amplitude, unsigned seed = 5) {
  const std::vector<J>& js = figure();
  std::vector<std::vector<int>> kids(js.size());
  for (size_t i = 1; i < js.size(); ++i) kids[js[i].parent].push_back(static_cast<int>(i));
  std::string out = "HIERARCHY\n";
  std::vector<int> order;
  std::function<void(int, int)> emit = [&](int i, int depth) {
    const std::string ind(depth, '\t');
    order.push_back(i);
    char buf[128];
    std::snprintf(buf, sizeof buf, "OFFSET %.6f %.6f %.6f", js[i].offset.x(), js[i].offset.y(),
                  js[i].offset.z());
    out += ind + (i == 0 ? "ROOT " : "JOINT ") + js[i].name + "\n" + ind + "{\n" + ind + "\t" +
           buf + "\n" + ind +
           "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
    for (int k : kids[i]) emit(k, depth + 1);
    if (kids[i].empty())
      out += ind + "\tEnd Site\n" + ind + "\t{\n" + ind + "\t\tOFFSET 0 5 0\n" + ind + "\t}\n";
    out += ind + "}\n";
  };
  emit(0, 0);
  out += "MOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: 0.0333333\n";
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int f = 0; f < frames; ++f) {
    for (int i : order) {
      const J& j = js[i];
      Vector3 p = j.position;
      if (i == 0)
        p += Vector3(0.8 * f, 2 * std::sin(0.3 * f), 0.4 * f);
      else if (j.moving)
        p += amplitude * Vector3(std::sin(0.5 * f), std::cos(0.7 * f), 0);
      else
        p += noise * Vector3(u(rng), u(rng), u(rng));
      const Vector3 a(30 * std::sin(0.1 * f + i), 20 * std::cos(0.13 * f + 2 * i),
                      45 * std::sin(0.07 * f - i));
      char buf[160];
      std::snprintf(buf, sizeof buf, "%.9f %.9f %.9f %.6f %.6f %.6f ", p.x(), p.y(), p.z(), a.x(),
                    a.y(), a.z());
      out += buf;
    }
    out += "\n";
  }
  return out;
}

struct Errors {
  double position = 0;
  double rotation = 0;
};

// the import's world poses of every node against the file's own (bvh_world_poses, scaled)
Errors against_file(const BvhDocument& doc, const BvhImport& imp) {
  Errors e;
  core::Data data(*imp.model);
  const double s = imp.layout.scale;
  for (int f = 0; f < doc.frames; ++f) {
    const auto X = core::forward_kinematics(*imp.model, data, imp.clip.frames[f]);
    const auto F = io::bvh_world_poses(doc, f);
    for (size_t k = 0; k < doc.nodes.size(); ++k) {
      const Transform& x = X[imp.node_link[k]];
      e.position = std::max(e.position, (x.p - s * F[k].p).norm());
      e.rotation = std::max(e.rotation, core::log3(x.R.transpose() * F[k].R).norm());
    }
  }
  return e;
}

// most converted joints above any node (Spine, Chest, LeftArm, LeftForeArm, LeftHand above
// Prop): the noise dropped at each adds up along the chain
int depth() { return 5; }

std::vector<std::string> constant_names() {
  std::vector<std::string> names;
  for (size_t i = 1; i < figure().size(); ++i) {
    if (!figure()[i].moving) names.push_back(figure()[i].name);
  }
  return names;
}

TEST(BvhConstantTranslation, NoisyConstantsBecomeSphericalMovingStaysFree) {
  const double noise = 1e-6;  // file units (cm)
  const std::string text = figure_bvh(90, noise, 3.0);
  const BvhDocument doc = io::parse_bvh(text, "six.bvh");
  const BvhImport imp = io::import_bvh(doc, "six.bvh");
  ASSERT_EQ(imp.unit, "centimetres");
  const core::Model& m = *imp.model;
  for (size_t i = 0; i < figure().size(); ++i) {
    const J& j = figure()[i];
    const JointType expected = i == 0 || j.moving ? JointType::kFree : JointType::kSpherical;
    EXPECT_EQ(m.joint_type[m.link_index(j.name)], expected) << j.name;
  }
  // 2 free joints (7 each) and 10 spherical (4 each) instead of 12 free
  EXPECT_EQ(m.nq, 2 * 7 + 10 * 4);
  EXPECT_EQ(imp.constant_translation_joints, constant_names());
  EXPECT_EQ(imp.translating_joints, std::vector<std::string>{"Prop"});
  // the rotational joint sits at the constant the channels hold, not at its OFFSET
  const int spine = m.link_index("Spine");
  EXPECT_LT((m.X_PJ[spine].p - 0.01 * Vector3(0, 10, -1)).norm(), 2 * 0.01 * noise);
  // world poses are the file's, to within the noise dropped along the chain (each component of a
  // joint's translation is moved by at most `noise` from the midrange)
  const Errors e = against_file(doc, imp);
  EXPECT_LT(e.position, depth() * std::sqrt(3.0) * noise * 0.01);
  EXPECT_LT(e.rotation, 1e-12);
  std::printf("  noise %.0e cm: max position error %.3g m, rotation %.3g rad\n", noise, e.position,
              e.rotation);
}

TEST(BvhConstantTranslation, ExactConstantsKeepWorldPosesExactly) {
  const BvhDocument doc = io::parse_bvh(figure_bvh(60, 0.0, 3.0), "exact.bvh");
  const BvhImport imp = io::import_bvh(doc, "exact.bvh");
  EXPECT_EQ(imp.constant_translation_joints, constant_names());
  const Errors e = against_file(doc, imp);
  EXPECT_LT(e.position, 1e-9);
  EXPECT_LT(e.rotation, 1e-12);
}

TEST(BvhConstantTranslation, ToleranceIsRelativeToTheFigure) {
  // the figure's largest rest extent: 95 + ... in centimetres; the tolerance in file units
  const BvhDocument probe = io::parse_bvh(figure_bvh(2, 0.0, 0.0), "probe.bvh");
  const double tol_units =
      io::kBvhConstantTranslationTolerance * io::bvh_rest_extent(probe).largest;
  // Prop moving by half the tolerance: constant; by twice the tolerance: free
  for (const double k : {0.5, 2.0}) {
    const BvhImport imp =
        io::import_bvh(io::parse_bvh(figure_bvh(40, 0.0, k * tol_units), "p.bvh"), "p.bvh");
    const int prop = imp.model->link_index("Prop");
    EXPECT_EQ(imp.model->joint_type[prop], k < 1 ? JointType::kSpherical : JointType::kFree) << k;
  }
  // the choice does not depend on the unit: deviations and the figure scale alike
  for (const double scale : {1.0, 0.001}) {
    BvhImportOptions o;
    o.scale = scale;
    for (const double k : {0.5, 2.0}) {
      const BvhImport imp = io::load_bvh_string(figure_bvh(40, 0.0, k * tol_units), "p.bvh", o);
      const int prop = imp.model->link_index("Prop");
      EXPECT_EQ(imp.model->joint_type[prop], k < 1 ? JointType::kSpherical : JointType::kFree)
          << k << " at scale " << scale;
    }
  }
}

TEST(BvhConstantTranslation, OneFrameConvertsNoFrameStaysFree) {
  const BvhImport one = io::load_bvh_string(figure_bvh(1, 0.0, 3.0), "one.bvh");
  EXPECT_EQ(one.translating_joints, std::vector<std::string>{});
  EXPECT_EQ(one.constant_translation_joints.size(), figure().size() - 1);
  // no frames: nothing shows the translation constant; the joints stay as the channels say
  std::string text = figure_bvh(1, 0.0, 3.0);
  const size_t at = text.find("Frames: 1");
  ASSERT_NE(at, std::string::npos);
  text = text.substr(0, at) + "Frames: 0\nFrame Time: 0.0333333\n";
  BvhDocument doc;
  try {
    doc = io::parse_bvh(text, "none.bvh");
  } catch (const core::ModelError& e) {
    GTEST_SKIP() << "the reader refuses Frames: 0: " << e.what();
  }
  const BvhImport none = io::import_bvh(doc, "none.bvh");
  EXPECT_EQ(none.constant_translation_joints, std::vector<std::string>{});
  EXPECT_EQ(none.translating_joints.size(), figure().size() - 1);
}

TEST(BvhConstantTranslation, ExportReadsBackToTheSamePoses) {
  const std::string text = figure_bvh(90, 1e-6, 3.0);
  const BvhImport a = io::load_bvh_string(text, "six.bvh");
  io::BvhExportOptions x;
  x.layout = &a.layout;
  const std::string written = io::write_bvh(*a.model, a.clip, x);
  const BvhDocument d = io::parse_bvh(written, "again.bvh");
  // converted joints are written with their rotation channels over the constant OFFSET
  for (const io::BvhNode& n : d.nodes) {
    if (n.is_end_site() || n.parent < 0) continue;
    EXPECT_EQ(n.channels.size(), n.name == "Prop" ? 6u : 3u) << n.name;
  }
  const BvhImport b = io::import_bvh(d, "again.bvh");
  EXPECT_EQ(b.model->nq, a.model->nq);
  EXPECT_EQ(b.constant_translation_joints, std::vector<std::string>{});  // no position channels
  EXPECT_EQ(b.translating_joints, std::vector<std::string>{"Prop"});
  ASSERT_EQ(a.node_link.size(), b.node_link.size());
  ASSERT_EQ(a.clip.size(), b.clip.size());
  core::Data da(*a.model), db(*b.model);
  double position = 0, rotation = 0;
  for (int f = 0; f < a.clip.size(); ++f) {
    const auto xa = core::forward_kinematics(*a.model, da, a.clip.frames[f]);
    const auto xb = core::forward_kinematics(*b.model, db, b.clip.frames[f]);
    for (size_t k = 0; k < a.node_link.size(); ++k) {
      const Transform& p = xa[a.node_link[k]];
      const Transform& q = xb[b.node_link[k]];
      position = std::max(position, (p.p - q.p).norm());
      rotation = std::max(rotation, core::log3(p.R.transpose() * q.R).norm());
    }
  }
  // the writer's 6 decimals: 5e-9 m per coordinate, 1e-8 rad per angle over about a metre
  EXPECT_LT(position, 1e-6);
  EXPECT_LT(rotation, 1e-6);
  std::printf("  round trip: max position error %.3g m, rotation %.3g rad\n", position, rotation);
}

// A clip loaded onto a character follows the character's joint types: a take where Prop happens
// to stand still keeps Prop free on a character that has it free, and a take where Prop moves is
// refused, naming Prop, on a character that has it rotational.
TEST(BvhConstantTranslation, AClipFollowsTheJointTypesOfTheCharacterItIsLoadedOnto) {
  const BvhImport moving = io::load_bvh_string(figure_bvh(40, 1e-6, 3.0), "moving.bvh");
  const BvhImport still = io::load_bvh_string(figure_bvh(40, 1e-6, 0.0, 7), "still.bvh");
  const core::Model& free_prop = *moving.model;
  const core::Model& rotational_prop = *still.model;
  ASSERT_EQ(free_prop.joint_type[free_prop.link_index("Prop")], JointType::kFree);
  ASSERT_EQ(rotational_prop.joint_type[rotational_prop.link_index("Prop")], JointType::kSpherical);

  BvhImportOptions onto_free;
  onto_free.joint_types_of = &free_prop;
  const BvhImport a = io::load_bvh_string(figure_bvh(40, 1e-6, 0.0, 7), "still.bvh", onto_free);
  EXPECT_EQ(a.model->joint_type, free_prop.joint_type);
  EXPECT_EQ(a.model->nq, free_prop.nq);
  EXPECT_EQ(a.translating_joints, std::vector<std::string>{"Prop"});
  // its world poses are still the file's
  const Errors e = against_file(io::parse_bvh(figure_bvh(40, 1e-6, 0.0, 7), "still.bvh"), a);
  EXPECT_LT(e.position, depth() * std::sqrt(3.0) * 1e-6 * 0.01);

  BvhImportOptions onto_rotational;
  onto_rotational.joint_types_of = &rotational_prop;
  try {
    io::load_bvh_string(figure_bvh(40, 1e-6, 3.0), "moving.bvh", onto_rotational);
    ADD_FAILURE() << "a translating Prop was loaded onto a rotational one";
  } catch (const core::ModelError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("moving.bvh"), std::string::npos) << what;
    EXPECT_NE(what.find("\"Prop\" translates"), std::string::npos) << what;
  }
}

// `pindrag info` as the executable

using fixtures::Outcome;

Outcome pindrag(const gltf_test::TempDir& dir, const std::string& args) {
  return fixtures::run_pindrag(PINDRAG_EXE, dir.path(""), args);
}

TEST(BvhConstantTranslation, InfoReportsConstantAndTranslatingJoints) {
  gltf_test::TempDir dir;
  const std::string path = dir.path("six.bvh");
  {
    std::ofstream f(path, std::ios::binary);
    f << figure_bvh(30, 1e-6, 3.0);
  }
  const Outcome r = pindrag(dir, "info " + path);
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  const nlohmann::json& clip = j.at("clip");
  EXPECT_EQ(clip.at("constant_translations").get<std::vector<std::string>>(), constant_names());
  EXPECT_EQ(clip.at("translating_joints").get<std::vector<std::string>>(),
            std::vector<std::string>{"Prop"});
  EXPECT_EQ(j.at("joints").at(core::to_string(JointType::kSpherical)), 10);
  EXPECT_EQ(j.at("joints").at(core::to_string(JointType::kFree)), 2);
  EXPECT_EQ(j.at("nq"), 2 * 7 + 10 * 4);
  // a file whose non-root joints only rotate: both lists empty
  if (!fixtures::data_dir().empty()) {
    const std::string walk = fixtures::data_dir() + "/bvh/cmu_walk_cgspeed.bvh";
    if (std::ifstream(walk).good()) {
      const Outcome w = pindrag(dir, "info " + walk);
      ASSERT_EQ(w.status, 0) << w.err;
      const nlohmann::json k = nlohmann::json::parse(w.out);
      EXPECT_TRUE(k.at("clip").at("constant_translations").empty());
      EXPECT_TRUE(k.at("clip").at("translating_joints").empty());
    }
  }
}

}  // namespace
