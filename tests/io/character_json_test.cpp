// Tests for io/character_json.hpp: exact round trips (fixtures, a model with every feature,
// random trees), hand-authored rotations, the written form, warnings, atomic saving, and a corpus
// of malformed and hostile files that must each fail with the file, the field and the rule.
#include "io/character_json.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>

#include "core/swing_twist.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;
using core::Geometry;
using core::JointType;
using core::LinkSpec;
using core::Matrix3;
using core::ModelBuilder;
using core::ModelError;
using core::Quaternion;
using core::Transform;
using core::Vector3;
using io::load_character_json_file;
using io::load_character_json_string;
using io::LoadResult;
using io::write_character_json;

constexpr double kPi = 3.14159265358979323846;

LoadResult load(const std::string& text, const std::string& name = "test.json") {
  return load_character_json_string(text, name, "");
}

// Loads and expects a ModelError whose message holds every fragment; returns the message.
std::string expect_error(const std::function<void()>& f,
                         const std::vector<std::string>& fragments) {
  try {
    f();
  } catch (const ModelError& e) {
    const std::string msg = e.what();
    for (const auto& frag : fragments) EXPECT_NE(msg.find(frag), std::string::npos) << msg;
    return msg;
  }
  ADD_FAILURE() << "no ModelError";
  return "";
}

// The two round-trip properties: equal model, byte-identical second write.
void expect_round_trip(const core::Model& m) {
  const std::string text = write_character_json(m);
  const LoadResult r = load(text);
  ASSERT_TRUE(r.model);
  EXPECT_TRUE(*r.model == m) << text;
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  EXPECT_EQ(write_character_json(*r.model), text);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string json_fixture_dir() { return fixtures::source_dir() + "/tests/fixtures/json"; }
std::string malformed_dir() { return fixtures::source_dir() + "/tests/fixtures/malformed/json"; }

// URDF-style fixed-axis roll, pitch, yaw written out entry by entry: R = Rz(y) Ry(p) Rx(r)
Matrix3 rpy_matrix(double r, double p, double y) {
  const double cr = std::cos(r), sr = std::sin(r), cp = std::cos(p), sp = std::sin(p),
               cy = std::cos(y), sy = std::sin(y);
  Matrix3 R;
  R << cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,  //
      sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,   //
      -sp, cp * sr, cp * cr;
  return R;
}

// A model that uses every field the format carries.
std::shared_ptr<const core::Model> every_feature_model() {
  ModelBuilder b("every feature");
  b.set_gravity(Vector3(0.3, -3.71, 0.05));

  LinkSpec pelvis = fixtures::box_link("pelvis", "", 11.3, Vector3(0.15, 0.1, 0.12));
  pelvis.display_name = "Pelvis";
  pelvis.joint.type = JointType::kFree;
  pelvis.joint.X_PJ = {Eigen::AngleAxisd(0.2, Vector3(0.3, 1, 0.1).normalized()).toRotationMatrix(),
                       Vector3(0.01, 0.95, -0.02)};
  pelvis.joint.ik_weight = 0.25;
  pelvis.joint.ik_gain = 40.0;
  pelvis.com = Vector3(0.003, 0.021, -0.0107);
  pelvis.I_com(0, 1) = pelvis.I_com(1, 0) = 0.0031;
  pelvis.I_com(1, 2) = pelvis.I_com(2, 1) = -0.0017;
  Geometry cap;
  cap.shape = Geometry::Shape::kCapsule;
  cap.radius = 0.11;
  cap.length = 0.17;
  cap.X_LinkShape = {Eigen::AngleAxisd(kPi / 2, Vector3::UnitY()).toRotationMatrix(),
                     Vector3(0, 0.05, 0)};
  pelvis.collision.push_back(cap);
  Geometry mesh;
  mesh.shape = Geometry::Shape::kMesh;
  mesh.mesh = "meshes/pelvis.obj";
  mesh.scale = Vector3(0.01, 0.01, 0.0125);
  mesh.X_LinkShape.p = Vector3(0, -0.01, 0);
  pelvis.visual.push_back(mesh);
  b.add_link(pelvis);

  // spherical, directional range with twist limits beyond ±π, a range frame, a rest orientation
  LinkSpec spine = fixtures::box_link("spine", "pelvis", 7.7, Vector3(0.13, 0.15, 0.1));
  spine.display_name = "Spine — lumbar";
  spine.joint.name = "lumbar";
  spine.joint.type = JointType::kSpherical;
  spine.joint.X_PJ.p = Vector3(0, 0.11, -0.013);
  spine.joint.range =
      core::directional_range({0, 1.3, 2.5, 3.9, 5.1}, {0.6, 0.4, 0.9, 0.3, 0.5},
                              {-3.5, -1, 2.5, -0.2, -4.0}, {3.7, 1.2, 4.4, 0.3, -2.9}, -3.3, 3.3);
  spine.joint.range.frame = Quaternion(Eigen::AngleAxisd(0.7, Vector3(1, -2, 0.5).normalized()));
  spine.joint.standard_orientation =
      Quaternion(Eigen::AngleAxisd(0.15, Vector3(0.2, 0.1, 1).normalized()));
  spine.joint.ik_gain = 7.5;
  spine.com = Vector3(0, 0.1, 0.01);
  b.add_link(spine);

  LinkSpec head = fixtures::box_link("head", "spine", 4.1, Vector3(0.09, 0.11, 0.1));
  head.joint.type = JointType::kSpherical;
  head.joint.X_PJ.p = Vector3(0, 0.3, 0);
  head.joint.range = core::cone_range(0.7, -1.1, 1.1, 5);
  Geometry sphere;
  sphere.shape = Geometry::Shape::kSphere;
  sphere.radius = 0.1;
  sphere.X_LinkShape.p = Vector3(0, 0.1, 0.02);
  head.collision.push_back(sphere);
  b.add_link(head);

  // revolute, oblique axis, all four limits finite
  LinkSpec upper = fixtures::box_link("upper_arm_l", "spine", 2.1, Vector3(0.14, 0.04, 0.04));
  upper.display_name = "Oberarm links";
  upper.joint.name = "shoulder_l";
  upper.joint.type = JointType::kRevolute;
  upper.joint.axis = Vector3(1, 2, 3);
  upper.joint.X_PJ = {Eigen::AngleAxisd(-0.4, Vector3::UnitZ()).toRotationMatrix(),
                      Vector3(0.19, 0.25, 0)};
  upper.joint.limits = {-2.1, 1.3, 6.5, 80};
  upper.com = Vector3(0.13, 0, 0);
  Geometry cyl;
  cyl.shape = Geometry::Shape::kCylinder;
  cyl.radius = 0.04;
  cyl.length = 0.26;
  cyl.X_LinkShape = {Eigen::AngleAxisd(kPi / 2, Vector3::UnitY()).toRotationMatrix(),
                     Vector3(0.13, 0, 0)};
  upper.collision.push_back(cyl);
  b.add_link(upper);

  // revolute, only the lower limit finite
  LinkSpec fore = fixtures::box_link("forearm_l", "upper_arm_l", 1.3, Vector3(0.12, 0.03, 0.03));
  fore.joint.type = JointType::kRevolute;
  fore.joint.axis = Vector3::UnitY();
  fore.joint.X_PJ.p = Vector3(0.28, 0, 0);
  fore.joint.limits.lower = 0;
  fore.com = Vector3(0.121, 0.001, 0);
  Geometry box;
  box.shape = Geometry::Shape::kBox;
  box.size = Vector3(0.24, 0.05, 0.06);
  box.X_LinkShape.p = Vector3(0.12, 0, 0);
  fore.collision.push_back(box);
  fore.visual.push_back(box);
  b.add_link(fore);

  // massless fixed link with a rotated placement
  LinkSpec hand;
  hand.name = "hand_l";
  hand.parent = "forearm_l";
  hand.display_name = "Hand";
  hand.joint.type = JointType::kFixed;
  hand.joint.X_PJ = {Eigen::AngleAxisd(0.3, Vector3(1, 1, 1).normalized()).toRotationMatrix(),
                     Vector3(0.25, 0, 0)};
  hand.joint.ik_weight = 0;
  b.add_link(hand);

  // prismatic, only the upper and effort limits finite
  LinkSpec slide = fixtures::box_link("slider", "pelvis", 0.37, Vector3(0.02, 0.02, 0.02));
  slide.joint.type = JointType::kPrismatic;
  slide.joint.axis = Vector3(0.3, -0.4, 0.5);
  slide.joint.limits.upper = 0.15;
  slide.joint.limits.effort = 200;
  b.add_link(slide);

  // a point mass (no rotational inertia) off the joint axis, carried by a free joint below the root
  LinkSpec prop;
  prop.name = "prop";
  prop.parent = "hand_l";
  prop.joint.type = JointType::kFree;
  prop.mass = 0.173;
  prop.com = Vector3(0.031, -0.07, 0.011);
  b.add_link(prop);
  return b.finalize();
}

// A random tree whose values have no special structure: random masses over six decades, offset
// centres of mass, rotated inertias, oblique axes, random placements and quaternions.
std::shared_ptr<const core::Model> random_tree(int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  auto unit_quaternion = [&] { return Quaternion(U(rng), U(rng), U(rng), U(rng)).normalized(); };
  ModelBuilder b("random" + std::to_string(seed));
  for (int k = 0; k < n; ++k) {
    LinkSpec l;
    l.name = "l" + std::to_string(k);
    l.parent =
        k == 0 ? "" : "l" + std::to_string(std::uniform_int_distribution<int>(0, k - 1)(rng));
    const JointType types[] = {JointType::kRevolute, JointType::kPrismatic, JointType::kSpherical,
                               JointType::kFixed, JointType::kFree};
    l.joint.type = k == 0 ? JointType::kFree : types[rng() % 5];
    l.joint.X_PJ = {unit_quaternion().toRotationMatrix(), Vector3(U(rng), U(rng), U(rng))};
    l.joint.axis = Vector3(U(rng), U(rng), U(rng));
    if (l.joint.type == JointType::kSpherical) {
      l.joint.range = core::cone_range(0.3 + 0.5 * std::abs(U(rng)), -1 - std::abs(U(rng)),
                                       1 + std::abs(U(rng)), 3 + static_cast<int>(rng() % 5));
      l.joint.range.frame = unit_quaternion();
      l.joint.standard_orientation = unit_quaternion();
    }
    if (rng() % 2) l.joint.limits = {-std::abs(U(rng)), std::abs(U(rng)), 5, 50};
    l.mass = std::exp(7 * U(rng));
    l.com = std::exp(2 * U(rng)) * Vector3(U(rng), U(rng), U(rng));
    // principal moments that satisfy the triangle inequality, in a rotated frame
    const double a = std::abs(U(rng)), c = std::abs(U(rng));
    const double d = std::abs(a - c) + std::abs(U(rng)) * (a + c - std::abs(a - c));
    const Matrix3 R = unit_quaternion().toRotationMatrix();
    const Matrix3 I = l.mass * 1e-2 * R * Vector3(a, c, d).asDiagonal() * R.transpose();
    l.I_com = 0.5 * (I + I.transpose());
    if (k % 7 == 3) l.I_com.setZero();  // point masses
    l.joint.ik_weight = std::abs(U(rng));
    b.add_link(l);
  }
  return b.finalize();
}

// --------------------------------------------------------------------------------------------
// round trips

TEST(CharacterJson, BranchingTreeRoundTripsExactly) {
  expect_round_trip(*fixtures::branching_tree());
  expect_round_trip(*fixtures::branching_tree(Vector3(0, 0, -9.81)));
}

TEST(CharacterJson, ChainRoundTripsExactly) { expect_round_trip(*fixtures::chain(5)); }

TEST(CharacterJson, EveryFeatureRoundTripsExactly) {
  const auto m = every_feature_model();
  // the model really holds what the test claims
  const int spine = m->link_index("spine");
  ASSERT_GT(spine, 0);
  EXPECT_EQ(m->spherical_range[spine].triangles.size(), 5u);
  EXPECT_LT(m->spherical_range[spine].twist_lower.back(), -kPi);
  EXPECT_GT(m->spherical_range[spine].twist_upper[1], kPi);
  EXPECT_FALSE(m->spherical_range[spine].frame.coeffs() == Quaternion::Identity().coeffs());
  EXPECT_TRUE(std::isinf(m->limits[m->link_index("forearm_l")].upper));
  EXPECT_EQ(m->joint_name[m->link_index("upper_arm_l")], "shoulder_l");
  expect_round_trip(*m);

  const LoadResult r = load(write_character_json(*m));
  EXPECT_EQ(r.model->name, "every feature");
  EXPECT_EQ(r.model->gravity, Vector3(0.3, -3.71, 0.05));
  EXPECT_EQ(r.model->display_name[spine], "Spine — lumbar");
  EXPECT_EQ(*r.model->ik_gain[spine], 7.5);
}

TEST(CharacterJson, RandomTreesRoundTripExactly) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE(seed);
    const auto m = random_tree(120, seed);
    expect_round_trip(*m);
  }
}

// Why the writer searches for the inertia it writes: the plain inversion of the parallel-axis
// shift (c = h / m, I_c = I_O - m (|c|² E - c cᵀ)) either misses the stored spatial inertia in the
// last bit or leaves rounding residue that the builder rejects (a point mass gets a slightly
// negative principal moment); the round trip is exact regardless.
TEST(CharacterJson, PlainInertiaInversionWouldNotBeEnough) {
  // a star of 2000 links with random masses, offset centres of mass and rotated inertias
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-1, 1);
  ModelBuilder b("star");
  b.add_link(fixtures::box_link("hub", "", 1, Vector3(0.1, 0.1, 0.1)));
  for (int k = 0; k < 2000; ++k) {
    LinkSpec l;
    l.name = "s" + std::to_string(k);
    l.parent = "hub";
    l.mass = std::exp(6 * U(rng));
    l.com = std::exp(3 * U(rng)) * Vector3(U(rng), U(rng), U(rng));
    const Matrix3 R = Quaternion(U(rng), U(rng), U(rng), U(rng)).normalized().toRotationMatrix();
    const Vector3 moments(2.5 + 0.5 * U(rng), 2.5 + 0.5 * U(rng), 2.5 + 0.5 * U(rng));
    const Matrix3 I =
        std::exp(4 * U(rng)) * l.mass * 1e-2 * R * moments.asDiagonal() * R.transpose();
    l.I_com = 0.5 * (I + I.transpose());
    if (k % 9 == 0) l.I_com.setZero();  // point masses
    b.add_link(l);
  }
  const auto m = b.finalize();

  int inexact = 0, rejected = 0;
  for (int i = 1; i < m->njoints; ++i) {
    const core::SpatialInertia& S = m->inertia[i];
    const Vector3 c = S.com();
    const Matrix3 I = S.inertia_about_com();
    if (!(core::SpatialInertia::from_com(S.mass, c, I) == S)) ++inexact;
    ModelBuilder one("one");
    LinkSpec l;
    l.name = "a";
    l.mass = S.mass;
    l.com = c;
    l.I_com = I;
    one.add_link(l);
    try {
      one.finalize();
    } catch (const ModelError&) {
      ++rejected;
    }
  }
  std::printf("plain inversion: %d of %d inexact, %d rejected by the builder\n", inexact,
              m->nlinks(), rejected);
  EXPECT_GT(inexact, 0);
  EXPECT_GT(rejected, 0);
  expect_round_trip(*m);
}

// Inertias that the parallel-axis term swallows: a centre of mass far out compared with the radius
// of gyration (or a tiny inertia), so the stored inertia about the joint frame no longer holds the
// inertia about the COM to full precision. The writer must still find values the builder accepts
// and that reproduce the stored inertia (cases found by a randomized stress run).
TEST(CharacterJson, InertiaSwallowedByTheParallelAxisTermRoundTrips) {
  struct Case {
    double mass;
    Vector3 com;
    Vector3 moments;  // ixx, iyy, izz
    double ixy;
  };
  const Case cases[] = {
      {2.0,
       {-106871578.57206947, 1.0, 0.03943635366015872},
       {1.8376172352274804, 1.8376172352274804, 2.756425852841221},
       0.18376172352274805},
      {1.892964016476142e-27,
       {-5.903385948294167e+20, -3.6069877348231824e-100, -2.99823440478645e-216},
       {0.044278495582779354, 0.044278495582779354, 0.06641774337416903},
       0.0},
      {1.0,
       {1.825703768324941, 8.700099847603366e-10, -9.241449121947562e-09},
       {1.7701945324360594e-16, 1.7701945324360594e-16, 2.6552917986540894e-16},
       1.7701945324360595e-17},
      {4.8603994335612554e+101,
       {0.6319666377469507, 1.4214245954234238e-139, 0.3417653776050938},
       {0.08595015330545674, 0.08595015330545674, 0.12892522995818512},
       0.008595015330545675},
      {0.6693912674528656,
       {-67628.07087365948, -4.903432793863343e+15, -2.0},
       {788407051517894.0, 788407051517894.0, 1.182610577276841e+15},
       78840705151789.4},
  };
  ModelBuilder b("swallowed");
  b.add_link(fixtures::box_link("hub", "", 1, Vector3(0.1, 0.1, 0.1)));
  int k = 0;
  for (const Case& c : cases) {
    LinkSpec l;
    l.name = "c" + std::to_string(k++);
    l.parent = "hub";
    l.mass = c.mass;
    l.com = c.com;
    l.I_com = c.moments.asDiagonal();
    l.I_com(0, 1) = l.I_com(1, 0) = c.ixy;
    b.add_link(l);
  }
  expect_round_trip(*b.finalize());
}

// Why the loader keeps unit axes and quaternions bit for bit: renormalizing a unit vector can move
// its last bit, so the builder alone would not give load(write(m)) == m.
TEST(CharacterJson, RenormalizingUnitValuesIsNotIdempotent) {
  const auto m = random_tree(120, 3);
  int moved = 0, unit = 0;
  for (int i = 1; i < m->njoints; ++i) {
    if (m->joint_type[i] == JointType::kSpherical) {
      ++unit;
      if (m->standard_orientation[i].normalized().coeffs() != m->standard_orientation[i].coeffs()) {
        ++moved;
      }
    } else if (m->joint_type[i] == JointType::kRevolute ||
               m->joint_type[i] == JointType::kPrismatic) {
      ++unit;
      if (m->axis[i].normalized() != m->axis[i]) ++moved;
    }
  }
  EXPECT_GT(moved, 0) << "of " << unit;
  expect_round_trip(*m);
}

TEST(CharacterJson, SavedFileLoadsBackWithItsFolderAsSourceDir) {
  const fs::path dir = fs::temp_directory_path() / ("pindrag_json_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string path = (dir / "tree.json").string();
  const auto m = fixtures::branching_tree();
  io::save_character_json_file(*m, path);
  const LoadResult r = load_character_json_file(path);
  EXPECT_TRUE(*r.model == *m);
  EXPECT_EQ(fs::path(r.model->source_dir), dir.lexically_normal());

  // overwriting replaces the content and leaves no temporary file behind
  const auto chain = fixtures::chain(3);
  io::save_character_json_file(*chain, path);
  EXPECT_TRUE(*load_character_json_file(path).model == *chain);
  EXPECT_EQ(read_file(path), write_character_json(*chain));
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(e.path().filename(), "tree.json");
  }
  EXPECT_EQ(files, 1);

  // a folder that does not exist is an error that names the path
  const std::string missing = (dir / "no" / "such" / "x.json").string();
  try {
    io::save_character_json_file(*chain, missing);
    ADD_FAILURE() << "saved into a missing folder";
  } catch (const std::system_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// --------------------------------------------------------------------------------------------
// the written form

TEST(CharacterJson, WrittenFormUsesMatricesWxyzQuaternionsAndOmitsInfiniteLimits) {
  const auto m = every_feature_model();
  const nlohmann::json doc = nlohmann::json::parse(write_character_json(*m));
  EXPECT_EQ(doc["format"], "pindrag-character");
  EXPECT_EQ(doc["version"], 1);
  ASSERT_EQ(doc["links"].size(), static_cast<size_t>(m->nlinks()));

  std::map<std::string, nlohmann::json> by_name;
  for (const auto& l : doc["links"]) by_name[l["name"].get<std::string>()] = l;
  EXPECT_FALSE(by_name["pelvis"].contains("parent"));
  EXPECT_EQ(by_name["spine"]["parent"], "pelvis");

  // placements: row-major rotation matrix; identity rotations are omitted
  const auto& rot = by_name["upper_arm_l"]["joint"]["origin"]["rotation"];
  const Matrix3& R = m->X_PJ[m->link_index("upper_arm_l")].R;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(rot[r][c].get<double>(), R(r, c));
  }
  EXPECT_FALSE(by_name["forearm_l"]["joint"]["origin"].contains("rotation"));

  // quaternions [w, x, y, z]
  const Quaternion& s = m->standard_orientation[m->link_index("spine")];
  const auto& so = by_name["spine"]["joint"]["standard_orientation"];
  EXPECT_EQ(so[0].get<double>(), s.w());
  EXPECT_EQ(so[1].get<double>(), s.x());
  EXPECT_EQ(so[3].get<double>(), s.z());
  EXPECT_GT(so[0].get<double>(), 0.99);  // a small rotation: w is the large component

  // infinite limits are omitted, finite ones written
  const auto& fl = by_name["forearm_l"]["joint"]["limits"];
  EXPECT_EQ(fl["lower"], 0.0);
  EXPECT_FALSE(fl.contains("upper"));
  EXPECT_FALSE(fl.contains("velocity"));
  EXPECT_EQ(by_name["slider"]["joint"]["limits"]["effort"], 200.0);

  // range vertices [a_y, a_z, twist_lower, twist_upper]; a joint named like its link has no name
  const auto& v = by_name["spine"]["joint"]["range"]["vertices"];
  const core::SphericalRange& range = m->spherical_range[m->link_index("spine")];
  ASSERT_EQ(v.size(), range.swing.size());
  EXPECT_EQ(v[2][1].get<double>(), range.swing[2].y());
  EXPECT_EQ(v[2][3].get<double>(), range.twist_upper[2]);
  EXPECT_EQ(by_name["spine"]["joint"]["name"], "lumbar");
  EXPECT_FALSE(by_name["head"]["joint"].contains("name"));
  // massless link: no inertial block
  EXPECT_FALSE(by_name["hand_l"].contains("inertial"));
  EXPECT_EQ(by_name["prop"]["inertial"]["inertia"]["ixx"], 0.0);
}

TEST(CharacterJson, InfiniteLowerBoundAboveEverythingCannotBeWritten) {
  ModelBuilder b("m");
  LinkSpec l = fixtures::box_link("a", "", 1, Vector3(0.1, 0.1, 0.1));
  l.joint.type = JointType::kRevolute;
  l.joint.limits.lower = core::kInfinity;  // accepted by the builder (lower <= upper = +inf)
  b.add_link(l);
  EXPECT_THROW(write_character_json(*b.finalize()), std::invalid_argument);
}

// --------------------------------------------------------------------------------------------
// hand-authored input

TEST(CharacterJson, HandAuthoredRotationsLoadToTheExpectedMatrices) {
  const LoadResult r = load_character_json_file(json_fixture_dir() + "/hand_authored_arm.json");
  const core::Model& m = *r.model;
  ASSERT_EQ(m.nlinks(), 4);
  EXPECT_EQ(m.name, "hand-authored arm");
  EXPECT_EQ(m.gravity, Vector3(0, -9.81, 0));  // default

  const int torso = m.link_index("torso"), arm = m.link_index("upper_arm"),
            fore = m.link_index("forearm"), hand = m.link_index("hand");
  // rpy [0, 0, π/2]: a quarter turn about +z (yaw)
  Matrix3 Rz90;
  Rz90 << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_TRUE(m.X_PJ[torso].R.isApprox(Rz90, 1e-15)) << m.X_PJ[torso].R;
  EXPECT_EQ(m.X_PJ[torso].p, Vector3(0, 1, 0));
  // quaternion [√½, √½, 0, 0]: a quarter turn about +x
  Matrix3 Rx90;
  Rx90 << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  ASSERT_EQ(m.collision[torso].size(), 1u);
  EXPECT_LT((m.collision[torso][0].X_LinkShape.R - Rx90).cwiseAbs().maxCoeff(), 1e-15);
  // quaternion [√½, 0, √½, 0]: a quarter turn about +y
  Matrix3 Ry90;
  Ry90 << 0, 0, 1, 0, 1, 0, -1, 0, 0;
  EXPECT_LT((m.X_PJ[arm].R - Ry90).cwiseAbs().maxCoeff(), 1e-15);
  // rpy [0.1, 0.2, 0.3] against the entry-by-entry formula
  EXPECT_LT((m.X_PJ[fore].R - rpy_matrix(0.1, 0.2, 0.3)).cwiseAbs().maxCoeff(), 1e-15);
  // [0.7071, 0, 0, 0.7071] is not unit to rounding: normalized, a quarter turn about +z
  EXPECT_LT((m.X_PJ[hand].R - Rz90).cwiseAbs().maxCoeff(), 1e-15);

  // other hand-authored conveniences
  EXPECT_EQ(m.axis[fore], Vector3::UnitZ());  // [0, 0, 2] normalized
  EXPECT_EQ(m.axis_index[fore], 2);
  EXPECT_EQ(m.joint_name[fore], "elbow");
  EXPECT_EQ(m.joint_name[hand], "hand");  // defaults to the link name
  EXPECT_EQ(m.limits[fore].lower, 0.0);
  EXPECT_EQ(m.limits[fore].upper, 2.5);
  EXPECT_TRUE(std::isinf(m.limits[fore].velocity));
  EXPECT_EQ(m.ik_weight[arm], 0.5);
  EXPECT_EQ(m.ik_weight[fore], 1.0);
  EXPECT_EQ(*m.ik_gain[fore], 15.0);
  EXPECT_FALSE(m.ik_gain[arm].has_value());
  EXPECT_NEAR(m.standard_orientation[arm].z(), std::sin(kPi / 8), 1e-16);
  EXPECT_EQ(m.spherical_range[arm].triangles.size(), 4u);
  EXPECT_EQ(m.spherical_range[arm].twist_lower[1], -1.2);
  EXPECT_EQ(m.display_name[arm], "Upper arm (left)");
  EXPECT_EQ(m.inertia[torso].mass, 10.0);
  EXPECT_TRUE(m.inertia[torso].com().isApprox(Vector3(0, 0.2, 0), 1e-15));
  // inertia given as a 3×3 matrix
  EXPECT_NEAR(m.inertia[fore].inertia_about_com()(1, 1), 0.006, 1e-15);
  EXPECT_EQ(m.inertia[hand].mass, 0.0);
  EXPECT_EQ(m.collision[hand][0].size, Vector3(0.08, 0.02, 0.1));
  EXPECT_EQ(m.visual[fore][0].mesh, "meshes/forearm.obj");
  EXPECT_EQ(m.visual[fore][0].scale, Vector3(0.01, 0.01, 0.01));

  // the referenced mesh is not in the repository: a warning that names the field
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("hand_authored_arm.json: /links/2/visual/0/mesh: mesh file"),
            std::string::npos)
      << r.warnings[0];
  // and what was loaded round-trips
  expect_round_trip(m);
}

TEST(CharacterJson, DocumentedExampleLoads) {
  const std::string doc = read_file(fixtures::source_dir() + "/docs/character-format.md");
  const size_t start = doc.find("```json\n");
  ASSERT_NE(start, std::string::npos);
  const size_t end = doc.find("```", start + 8);
  ASSERT_NE(end, std::string::npos);
  const LoadResult r = load(doc.substr(start + 8, end - start - 8), "example.json");
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const core::Model& m = *r.model;
  EXPECT_EQ(m.name, "two-link arm");
  ASSERT_EQ(m.nlinks(), 3);
  EXPECT_EQ(m.joint_type[m.link_index("upper_arm")], JointType::kSpherical);
  EXPECT_EQ(m.spherical_range[m.link_index("upper_arm")].triangles.size(), 4u);
  expect_round_trip(m);
}

TEST(CharacterJson, ExtremeButFiniteValuesLoadAndRoundTrip) {
  const std::string text = R"({
    "format": "pindrag-character", "version": 1, "gravity": [0, -1e-300, 0],
    "links": [
      {"name": "root", "joint": {"type": "free", "origin": {"xyz": [1e300, -0.0, 5e-324]}},
       "inertial": {"mass": 1e-300, "com": [1e-10, 3e-9, 0], )"
                           R"("inertia": {"ixx": 1e-310, "iyy": 1e-310, "izz": 1e-310}}},
      {"name": "arm", "parent": "root",
       "joint": {"type": "revolute", "axis": [1e200, 1e200, 0], )"
                           R"("limits": {"lower": -1e308, "upper": 1e308}}},
      {"name": "leg", "parent": "root", "joint": {"type": "prismatic", "axis": [3e-5, 0, -4e-5]}}
    ]})";
  const LoadResult r = load(text);
  const core::Model& m = *r.model;
  // huge and tiny axes are scaled without overflow or underflow
  EXPECT_TRUE(m.axis[m.link_index("arm")].isApprox(Vector3(1, 1, 0).normalized(), 1e-15));
  EXPECT_TRUE(m.axis[m.link_index("leg")].isApprox(Vector3(0.6, 0, -0.8), 1e-15));
  EXPECT_EQ(m.X_PJ[1].p.z(), 5e-324);
  EXPECT_EQ(m.limits[m.link_index("arm")].upper, 1e308);
  expect_round_trip(m);
}

TEST(CharacterJson, UnknownAndIgnoredKeysAreWarningsWithPointers) {
  const std::string text = R"({
    "format": "pindrag-character", "version": 1, "author": "me",
    "links": [
      {"name": "root", "colour": "red", "joint": {"type": "free", "axis": [1, 0, 0]},
       "inertial": {"mass": 1, "inertia": {"ixx": 0.1, "iyy": 0.1, "izz": 0.1, "izx": 0}},
       "collision": [{"shape": "box", "size": [0.1, 0.1, 0.1], "radius": 0.3}]},
      {"name": "arm", "parent": "root",
       "joint": {"type": "spherical", "limits": {"lower": 0}, )"
                           R"("standard_orientation": [1, 0, 0, 0]}},
      {"name": "leg", "parent": "root",
       "joint": {"type": "revolute", "standard_orientation": [1, 0, 0, 0], )"
                           R"("origin": {"xzy": [0, 0, 0]}}}
    ]})";
  const LoadResult r = load(text, "warn.json");
  std::set<std::string> w(r.warnings.begin(), r.warnings.end());
  auto has = [&](const std::string& fragment) {
    for (const auto& s : w) {
      if (s.find(fragment) != std::string::npos) return true;
    }
    return false;
  };
  EXPECT_TRUE(has("warn.json: /author: unknown key"));
  EXPECT_TRUE(has("warn.json: /links/0/colour: unknown key"));
  EXPECT_TRUE(has("warn.json: /links/0/inertial/inertia/izx: unknown key"));
  EXPECT_TRUE(has("warn.json: /links/0/joint/axis: ignored: a free joint has no axis"));
  EXPECT_TRUE(has("warn.json: /links/0/collision/0/radius: not used by a box (kept)"));
  EXPECT_TRUE(has("warn.json: /links/1/joint/limits: ignored: a spherical joint has no limits"));
  EXPECT_TRUE(has("warn.json: /links/2/joint/standard_orientation: ignored"));
  EXPECT_TRUE(has("warn.json: /links/2/joint/origin/xzy: unknown key"));
  EXPECT_EQ(r.warnings.size(), 8u);
  // the unused radius is kept, so the model still round-trips
  EXPECT_EQ(r.model->collision[1][0].radius, 0.3);
  const std::string again = write_character_json(*r.model);
  EXPECT_TRUE(*load(again).model == *r.model);
}

// --------------------------------------------------------------------------------------------
// malformed and hostile input

// Every file of tests/fixtures/malformed/json with the fragments its message must contain.
const std::map<std::string, std::vector<std::string>>& malformed_expectations() {
  static const std::map<std::string, std::vector<std::string>> table = {
      {"binary_garbage.json", {"binary_garbage.json: line 1, column", "syntax error"}},
      {"cycle.json",
       {"cycle.json: /links/1/parent: the parent links form a cycle", "'a'", "'c'",
        "rule: no cycles"}},
      {"duplicate_key.json", {"duplicate_key.json: /links/0/name: duplicate key", "unique"}},
      {"duplicate_link_names.json",
       {"duplicate_link_names.json: /links/2/name: link name 'arm' is also used by /links/1",
        "rule: link names are unique"}},
      {"empty.json", {"empty.json: line 1, column 1: the file is empty"}},
      {"fractional_index.json",
       {"fractional_index.json: /links/1/joint/range/triangles/0/1: expected an integer"}},
      {"inertia_triangle.json",
       {"inertia_triangle.json: /links/0/inertial/inertia:", "triangle inequality",
        "rule: I1 + I2 >= I3"}},
      {"inertia_overflows.json",
       {"inertia_overflows.json: /links/0/inertial: the inertia about the link frame overflows",
        "inertia_overflows.json: /links/1/inertial: the inertia about the link frame overflows"}},
      {"invalid_utf8.json", {"invalid_utf8.json: line 1, column", "UTF-8"}},
      {"lower_above_upper.json",
       {"lower_above_upper.json: /links/1/joint/limits: joint 'elbow': lower limit 1 > upper "
        "limit -1",
        "rule: lower <= upper"}},
      {"mesh_escapes_folder.json",
       {"mesh_escapes_folder.json: /links/0/visual/0/mesh: mesh path leaves", "rule: no '..'"}},
      {"missing_parent.json",
       {"missing_parent.json: /links/1/parent: parent link 'torso' does not exist"}},
      {"nan_as_string.json",
       {"nan_as_string.json: /links/0/inertial/mass: expected a number, got a string"}},
      {"negative_ik_weight.json",
       {"negative_ik_weight.json: /links/0/joint/ik/weight:", "IK weight must be finite and >= 0"}},
      {"negative_mass.json",
       {"negative_mass.json: /links/1/inertial/mass: link 'arm': mass -2.5 is negative",
        "rule: mass must be >= 0"}},
      {"no_links.json", {"no_links.json: /links: no links (rule: at least one link)"}},
      {"non_unit_quaternion.json",
       {"non_unit_quaternion.json: /links/1/joint/standard_orientation: quaternion [w, x, y, z] "
        "has norm 5.4772",
        "rule: unit length"}},
      {"not_a_rotation.json",
       {"not_a_rotation.json: /links/1/joint/origin: joint 'elbow': placement is not a finite "
        "rigid transform"}},
      {"not_an_object.json",
       {"not_an_object.json: document root: expected an object, got an array"}},
      {"overflow_number.json",
       {"overflow_number.json: line 4, column", "number overflow parsing '1e999'"}},
      {"range_on_revolute.json",
       {"range_on_revolute.json: /links/1/joint/range: a revolute joint cannot have a swing-twist "
        "range"}},
      {"triangle_index_out_of_range.json",
       {"triangle_index_out_of_range.json: /links/1/joint/range/triangles/1/2: vertex index 9 is "
        "out of range",
        "0 <= index < 4"}},
      {"truncated.json", {"truncated.json: line 6, column 115:", "missing closing quote"}},
      {"twist_lower_above_upper.json",
       {"twist_lower_above_upper.json: /links/1/joint/range/vertices/1: joint 'hip': range vertex "
        "1: twist lower 2 > upper 1"}},
      {"two_roots.json",
       {"two_roots.json: /links/1/parent: missing, so link 'stray' is a second root",
        "rule: exactly one link has no parent"}},
      {"two_rotations.json",
       {"two_rotations.json: /links/0/joint/origin: gives more than one of rotation, quaternion "
        "and rpy"}},
      {"unknown_joint_type.json",
       {"unknown_joint_type.json: /links/1/joint/type: unknown joint type 'ball'"}},
      {"unsupported_version.json",
       {"unsupported_version.json: /version: version 2 is not supported"}},
      {"vertex_outside_disk.json",
       {"vertex_outside_disk.json: /links/1/joint/range/vertices/2:", "outside the unit disk",
        "rule: |a| <= 1"}},
      {"wrong_format.json", {"wrong_format.json: /format: is 'urdf'", "pindrag-character"}},
      {"wrong_types.json",
       {"wrong_types.json: /gravity: expected an array of 3 numbers, got a string",
        "wrong_types.json: /links/0/name: expected a string, got a number",
        "wrong_types.json: /links/1/joint/axis/1: expected a number, got a string",
        "wrong_types.json: /links/1/collision: expected an array, got an object"}},
      {"zero_radius_capsule.json",
       {"zero_radius_capsule.json: /links/0/collision/0/radius:", "radius must be > 0"}},
  };
  return table;
}

TEST(CharacterJson, EveryMalformedFileFailsNamingFileFieldAndRule) {
  const auto& table = malformed_expectations();
  std::set<std::string> seen;
  for (const auto& e : fs::directory_iterator(malformed_dir())) {
    const std::string name = e.path().filename().string();
    seen.insert(name);
    SCOPED_TRACE(name);
    const auto it = table.find(name);
    ASSERT_NE(it, table.end()) << "no expectation for " << name;
    const std::string msg =
        expect_error([&] { load_character_json_file(e.path().string()); }, it->second);
    // every line names the file
    std::istringstream lines(msg);
    for (std::string line; std::getline(lines, line);) {
      EXPECT_EQ(line.rfind(e.path().string() + ": ", 0), 0u) << line;
    }
  }
  EXPECT_EQ(seen.size(), table.size()) << "an expected file is missing from the corpus";
}

TEST(CharacterJson, SyntaxErrorsGiveLineAndColumn) {
  // "tru" fails at the ']' that follows it: line 4, column 16
  const std::string text =
      "{\n  \"format\": \"pindrag-character\",\n  \"version\": 1,\n  \"links\": [tru]\n}\n";
  expect_error([&] { load(text, "syntax.json"); },
               {"syntax.json: line 4, column 16: syntax error while parsing value"});
  // columns count characters, not bytes: 'é' is two bytes and one column
  const std::string utf8 = "{\"name\": \"é\", x}";
  expect_error([&] { load(utf8, "utf8.json"); }, {"utf8.json: line 1, column 15:"});
}

TEST(CharacterJson, TooManyLinksAreRefusedBeforeBuilding) {
  std::string text = R"({"format": "pindrag-character", "version": 1, "links": [)";
  for (int k = 0; k <= core::kMaxLinks; ++k) {
    text += (k ? "," : "") + std::string(R"({"name": "l)") + std::to_string(k) + R"("})";
  }
  text += "]}";
  expect_error([&] { load(text, "many.json"); },
               {"many.json: /links: " + std::to_string(core::kMaxLinks + 1) + " links",
                "rule: at most " + std::to_string(core::kMaxLinks)});
}

TEST(CharacterJson, TooManyRangeTrianglesAreRefused) {
  // 9 joints with the largest range each: more triangles than one file may hold
  std::string range = R"({"vertices": [[0, 0, -1, 1])";
  const int n = core::kMaxRangeTriangles;
  for (int k = 0; k < n; ++k) {
    const double psi = 2 * kPi * k / n;
    range += ", [" + std::to_string(0.5 * std::cos(psi)) + ", " +
             std::to_string(0.5 * std::sin(psi)) + ", -1, 1]";
  }
  range += R"(], "triangles": [)";
  for (int k = 0; k < n; ++k) {
    range += (k ? ", [0, " : "[0, ") + std::to_string(1 + k) + ", " +
             std::to_string(1 + (k + 1) % n) + "]";
  }
  range += "]}";
  std::string text = R"({"format": "pindrag-character", "version": 1, )"
                     R"("links": [{"name": "r", "joint": {"type": "free"}})";
  for (int j = 0; j < 9; ++j) {
    text += R"(, {"name": "s)" + std::to_string(j) +
            R"(", "parent": "r", "joint": {"type": "spherical", "range": )" + range + "}}";
  }
  text += "]}";
  const std::string msg = expect_error(
      [&] { load(text, "ranges.json"); },
      {"ranges.json: /links/9/joint/range/triangles: the file holds more than 32768 range "
       "triangles in all"});
  EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 0);  // said once, not once per joint
}

TEST(CharacterJson, DeepNestingIsRefusedWithoutRecursion) {
  const int depth = 100000;
  const std::string arrays = std::string(depth, '[') + std::string(depth, ']');
  expect_error([&] { load(arrays, "deep.json"); },
               {"deep.json: line 1, column 65:", "nest deeper than 64 levels"});
  std::string objects;
  for (int k = 0; k < depth; ++k) objects += "{\"a\":";
  objects += "1" + std::string(depth, '}');
  expect_error([&] { load(objects, "deep_objects.json"); },
               {"deep_objects.json: line 1, column", "/a/a/a", "nest deeper than 64 levels"});
  // an unterminated deep prefix is refused the same way
  expect_error([&] { load(std::string(depth, '['), "open.json"); }, {"nest deeper than 64"});
}

TEST(CharacterJson, TooManyValuesAreRefused) {
  std::string text = R"({"format": "pindrag-character", "version": 1, "x": [)";
  text.reserve(text.size() + 2 * io::kMaxJsonValues + 8);
  for (size_t k = 0; k < io::kMaxJsonValues; ++k) text += "0,";
  text += "0]}";
  expect_error([&] { load(text, "values.json"); },
               {"values.json: /x/", "more than " + std::to_string(io::kMaxJsonValues)});
}

TEST(CharacterJson, OversizedFilesAreRefusedBeforeReading) {
  const fs::path path =
      fs::temp_directory_path() / ("pindrag_big_" + std::to_string(::getpid()) + ".json");
  { std::ofstream(path.string()) << "{"; }
  fs::resize_file(path, io::kMaxCharacterJsonBytes + 1);  // sparse: no disk used
  expect_error([&] { load_character_json_file(path.string()); },
               {path.string() + ": the file is 67108865 bytes", "at most 64 MiB"});
  fs::remove(path);
  expect_error([&] { load(std::string(io::kMaxCharacterJsonBytes + 1, ' '), "big.json"); },
               {"big.json:", "at most 64 MiB"});
  expect_error([&] { load_character_json_file("/nonexistent/dir/x.json"); },
               {"/nonexistent/dir/x.json: cannot open the file"});
  expect_error([&] { load_character_json_file(fs::temp_directory_path().string()); },
               {"not a regular file"});
}

TEST(CharacterJson, ManyErrorsAreCappedAndCounted) {
  std::string text = R"({"format": "pindrag-character", "version": 1, "links": [)";
  for (int k = 0; k < 300; ++k) text += (k ? "," : "") + std::string(R"({"name": 1})");
  text += "]}";
  const std::string msg = expect_error(
      [&] { load(text, "errs.json"); },
      {"errs.json: /links/0/name: expected a string", "errs.json: ... and 200 more errors"});
  EXPECT_EQ(std::count(msg.begin(), msg.end(), '\n'), 100);
}

}  // namespace
