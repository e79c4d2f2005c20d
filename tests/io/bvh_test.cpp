// Tests for io/bvh.hpp: rotation conventions against three.js's numbers, the liberal reader,
// a malformed corpus (file, line and rule in every message; bounded memory), the import, and round
// trips (our reader, three.js's BVHLoader in Node, assimp's CLI) for every shared BVH file, a
// synthetic skeleton with mixed orders and near-gimbal poses, and our own human figures.
#include "io/bvh.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
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
#include <regex>
#include <set>
#include <sstream>

#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/human_figure.hpp"
#include "core/kinematics.hpp"
#include "tests/fixtures/allocation_counter.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

namespace fs = std::filesystem;
using core::Matrix3;
using core::ModelError;
using core::Quaternion;
using core::Transform;
using core::Vector3;
using io::BvhChannel;
using io::BvhDocument;
using io::BvhExportOptions;
using io::BvhImport;
using io::BvhImportOptions;
using io::BvhNode;
using io::BvhRotationOrder;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string bvh_data_dir() { return fixtures::data_dir() + "/bvh"; }
std::string malformed_dir() { return fixtures::source_dir() + "/tests/fixtures/malformed/bvh"; }

std::vector<std::string> shared_files() {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(bvh_data_dir())) {
    if (e.path().extension() == ".bvh") files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// a scratch folder removed at the end of the test
struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("pindrag_bvh_test_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(std::random_device{}()));
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

// Runs a command line; returns its exit status and stdout.
std::pair<int, std::string> run(const std::string& command) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) return {-1, out};
  char buf[65536];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) out.append(buf, n);
  const int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

bool on_path(const std::string& tool) {
  return run("command -v " + tool + " >/dev/null 2>&1").first == 0;
}

// Expects f to throw a ModelError holding every fragment; returns the message.
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

double geodesic(const Matrix3& A, const Matrix3& B) { return core::log3(A.transpose() * B).norm(); }

// world poses of every model link for every frame
std::vector<std::vector<Transform>> posed(const core::Model& m, const core::Clip& clip) {
  core::Data data(m);
  std::vector<std::vector<Transform>> out;
  for (const Eigen::VectorXd& q : clip.frames) out.push_back(core::forward_kinematics(m, data, q));
  return out;
}

struct Errors {
  double position = 0;  // metres
  double rotation = 0;  // radians
};

// Compares two imports node by node (same file order): world positions and rotations of every
// joint and End Site, every frame.
Errors compare_nodes(const BvhImport& a, const BvhImport& b) {
  Errors e;
  EXPECT_EQ(a.node_link.size(), b.node_link.size());
  EXPECT_EQ(a.clip.size(), b.clip.size());
  if (a.node_link.size() != b.node_link.size() || a.clip.size() != b.clip.size()) return e;
  const auto pa = posed(*a.model, a.clip);
  const auto pb = posed(*b.model, b.clip);
  for (int f = 0; f < a.clip.size(); ++f) {
    for (size_t k = 0; k < a.node_link.size(); ++k) {
      const Transform& xa = pa[f][a.node_link[k]];
      const Transform& xb = pb[f][b.node_link[k]];
      e.position = std::max(e.position, (xa.p - xb.p).norm());
      e.rotation = std::max(e.rotation, geodesic(xa.R, xb.R));
    }
  }
  return e;
}

// Compares the links that both models have, by name: world positions and rotations.
Errors compare_links_by_name(const core::Model& ma,
                             const core::Clip& ca,
                             const core::Model& mb,
                             const core::Clip& cb,
                             int* compared = nullptr) {
  Errors e;
  EXPECT_EQ(ca.size(), cb.size());
  const auto pa = posed(ma, ca);
  const auto pb = posed(mb, cb);
  int n = 0;
  for (int i = 1; i < ma.njoints; ++i) {
    const int j = mb.link_index(io::sanitize_bvh_name(ma.link_name[i]));
    if (j < 1) continue;
    ++n;
    for (int f = 0; f < std::min(ca.size(), cb.size()); ++f) {
      e.position = std::max(e.position, (pa[f][i].p - pb[f][j].p).norm());
      e.rotation = std::max(e.rotation, geodesic(pa[f][i].R, pb[f][j].R));
    }
  }
  if (compared) *compared = n;
  return e;
}

std::vector<std::string> joint_names(const BvhDocument& d) {
  std::vector<std::string> names;
  for (const BvhNode& n : d.nodes) {
    if (!n.is_end_site()) names.push_back(n.name);
  }
  return names;
}

// ---------------------------------------------------------------------------------------------
// rotation conventions

TEST(BvhRotation, ZxyChannelsMatchThreeJs) {
  // ecosystem.md §1.3 [V]: channels Zrotation Xrotation Yrotation = 30, 40, 50 in three.js's
  // BVHLoader give the quaternion (x, y, z, w) = (0.19663, 0.46383, 0.36004, 0.78522)
  const std::string text =
      "HIERARCHY\nROOT a\n{\n\tOFFSET 0 0 0\n\tCHANNELS 3 Zrotation Xrotation Yrotation\n}\n"
      "MOTION\nFrames: 1\nFrame Time: 0.1\n30 40 50\n";
  const BvhDocument doc = io::parse_bvh(text, "zxy.bvh");
  const Quaternion q(io::bvh_joint_rotation(doc.nodes[0], doc.frame(0)));
  const double sign = q.w() < 0 ? -1 : 1;
  EXPECT_NEAR(sign * q.x(), 0.19663, 5e-6);
  EXPECT_NEAR(sign * q.y(), 0.46383, 5e-6);
  EXPECT_NEAR(sign * q.z(), 0.36004, 5e-6);
  EXPECT_NEAR(sign * q.w(), 0.78522, 5e-6);
  // the import stores the same rotation in the free root's quaternion
  const BvhImport imp = io::import_bvh(doc, "zxy.bvh");
  const Quaternion r = core::quaternion_at(imp.clip.frames[0], imp.model->idx_q[1] + 3);
  EXPECT_NEAR(std::abs(r.coeffs().dot(q.coeffs())), 1.0, 1e-12);
  // and the decomposition gives the file's angles back
  const Vector3 angles =
      io::matrix_to_euler(q.toRotationMatrix(), *io::parse_rotation_order("ZXY"));
  EXPECT_NEAR(angles[0] / kDeg, 30, 1e-9);
  EXPECT_NEAR(angles[1] / kDeg, 40, 1e-9);
  EXPECT_NEAR(angles[2] / kDeg, 50, 1e-9);
}

TEST(BvhRotation, ZxyDecompositionMatchesThreeJsFormulas) {
  // R = Rz(γ) Rx(α) Ry(β): α = asin(R21), β = atan2(−R20, R22), γ = atan2(−R01, R11)
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const BvhRotationOrder zxy = *io::parse_rotation_order("zxy");
  for (int k = 0; k < 200; ++k) {
    const Matrix3 R = Quaternion(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    const Vector3 a = io::matrix_to_euler(R, zxy);
    EXPECT_NEAR(a[1], std::asin(R(2, 1)), 1e-9);
    EXPECT_NEAR(a[2], std::atan2(-R(2, 0), R(2, 2)), 1e-9);
    EXPECT_NEAR(a[0], std::atan2(-R(0, 1), R(1, 1)), 1e-9);
  }
}

TEST(BvhRotation, EveryOrderRoundTripsIncludingGimbalLock) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-kPi, kPi);
  for (const char* name : {"XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"}) {
    const BvhRotationOrder order = *io::parse_rotation_order(name);
    EXPECT_EQ(io::to_string(order), name);
    for (int k = 0; k < 300; ++k) {
      Vector3 angles(u(rng), u(rng) / 2, u(rng));
      if (k % 3 == 1) angles[1] = (k % 2 ? 1 : -1) * 89.9 * kDeg;  // near gimbal lock
      if (k % 3 == 2) angles[1] = (k % 2 ? 1 : -1) * kPi / 2;      // at gimbal lock
      const Matrix3 R = io::euler_to_matrix(order, angles);
      const Vector3 back = io::matrix_to_euler(R, order);
      EXPECT_LT((io::euler_to_matrix(order, back) - R).norm(), 1e-12) << name << " " << k;
      if (k % 3 == 0) {
        EXPECT_LT((back - angles).norm(), 1e-9) << name;
      }
      // with a previous frame: the closest equivalent triple, still the same rotation
      const Vector3 prev = angles + Vector3(2 * kPi, -2 * kPi, 4 * kPi);
      const Vector3 near = io::matrix_to_euler(R, order, &prev);
      EXPECT_LT((io::euler_to_matrix(order, near) - R).norm(), 1e-12) << name;
      if (k % 3 != 2) {
        EXPECT_LT((near - prev).norm(), 1e-6) << name << " " << k;
      }
    }
  }
  EXPECT_FALSE(io::parse_rotation_order("XXY"));
  EXPECT_FALSE(io::parse_rotation_order("XY"));
  EXPECT_FALSE(io::parse_rotation_order("XYW"));
}

TEST(BvhRotation, UnwrapsAcrossPlusMinus180) {
  // a Z spin through ±180° and a middle angle through 90°: the angles stay continuous
  const BvhRotationOrder zxy = *io::parse_rotation_order("ZXY");
  Vector3 prev = Vector3::Zero();
  for (int f = 0; f <= 720; ++f) {
    const Vector3 a(f * kDeg, 30 * kDeg * std::sin(f * 0.05), 10 * kDeg);
    const Matrix3 R = io::euler_to_matrix(zxy, a);
    const Vector3 got = io::matrix_to_euler(R, zxy, f ? &prev : nullptr);
    if (f) {
      EXPECT_LT((got - prev).cwiseAbs().maxCoeff(), 3 * kDeg) << f;
    }
    EXPECT_NEAR(got[0], a[0], 1e-9) << f;  // 0 → 720°, no wrap back to -180
    prev = got;
  }
}

// ---------------------------------------------------------------------------------------------
// the reader

TEST(BvhReader, IsLiberalAboutLayoutCaseAndLineEndings) {
  const std::string text =
      "\xEF\xBB\xBFhierarchy\r\n\r\nroot   Hips {\r\n  offset\t1 2 3\r\n"
      "  channels 6 XPOSITION yposition Zposition zrotation XROTATION yrotation\r\n"
      "  JOINT Left Up Leg{\r\n\tOFFSET 0 -1 .5\r\n\tCHANNELS 3 Yrotation Zrotation Xrotation\r\n"
      "\tend site\r\n\t{ OFFSET 0 -2 0 }\r\n  }\r\n}\r\n\r\n"
      "Motion\r\nframes:\t2\r\nframe time: 0.01\r\n"
      "1 2 3 10 20 30 40 50 60 \r\n\r\n  -1e1 +2 3. 0 0 0 0 0 0\r\n\r\n";
  const BvhDocument d = io::parse_bvh(text, "liberal.bvh");
  ASSERT_EQ(d.nodes.size(), 3u);
  EXPECT_EQ(d.nodes[0].name, "Hips");
  EXPECT_EQ(d.nodes[0].kind, BvhNode::Kind::kRoot);
  EXPECT_EQ(d.nodes[1].name, "Left Up Leg");
  EXPECT_EQ(d.nodes[1].parent, 0);
  EXPECT_EQ(d.nodes[1].line, 6);
  EXPECT_TRUE(d.nodes[2].is_end_site());
  EXPECT_EQ(d.nodes[2].offset, Vector3(0, -2, 0));
  EXPECT_EQ(d.nodes[1].offset, Vector3(0, -1, 0.5));
  EXPECT_EQ(d.nodes[0].channels,
            (std::vector<BvhChannel>{BvhChannel::kXposition, BvhChannel::kYposition,
                                     BvhChannel::kZposition, BvhChannel::kZrotation,
                                     BvhChannel::kXrotation, BvhChannel::kYrotation}));
  EXPECT_EQ(d.nodes[1].channels,
            (std::vector<BvhChannel>{BvhChannel::kYrotation, BvhChannel::kZrotation,
                                     BvhChannel::kXrotation}));
  EXPECT_EQ(d.nodes[1].first_value, 6);
  EXPECT_EQ(d.channels, 9);
  EXPECT_EQ(d.frames, 2);
  EXPECT_DOUBLE_EQ(d.frame_time, 0.01);
  ASSERT_EQ(d.values.size(), 18u);
  EXPECT_EQ(d.values[8], 60.0);
  EXPECT_EQ(d.values[9], -10.0);
  EXPECT_EQ(d.values[10], 2.0);
  EXPECT_EQ(d.values[11], 3.0);
  EXPECT_TRUE(d.warnings.empty());
  // positions replace the OFFSET: root at (1, 2, 3) in frame 0, not (2, 4, 6)
  const auto X = io::bvh_world_poses(d, 0);
  EXPECT_LT((X[0].p - Vector3(1, 2, 3)).norm(), 1e-15);
  // the joint's rotation is Ry(40) Rz(50) Rx(60)
  const Matrix3 R = io::euler_to_matrix({1, 2, 0}, Vector3(40, 50, 60) * kDeg);
  EXPECT_LT((X[1].R - X[0].R * R).norm(), 1e-12);
}

TEST(BvhReader, NumbersParseExactly) {
  // the fast decimal path and from_chars agree bit for bit
  std::mt19937_64 rng(11);
  std::string line;
  std::vector<double> expected;
  const char* forms[] = {"%.6f", "%.4f", "%.15g", "%.17g", "%.3e", "%.0f", "%.12f"};
  for (int k = 0; k < 300; ++k) {
    const double v = std::ldexp(static_cast<double>(rng() % 2000000) - 1e6, -(int)(rng() % 20));
    char buf[64];
    std::snprintf(buf, sizeof buf, forms[k % 7], v);
    double w = 0;
    std::sscanf(buf, "%lf", &w);
    expected.push_back(w);
    line += std::string(buf) + " ";
  }
  std::string text =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n";
  for (int j = 1; j < 100; ++j) {
    text += "JOINT j" + std::to_string(j) +
            "\n{\nOFFSET 0 1 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n";
  }
  for (int j = 0; j < 100; ++j) text += "}\n";
  text += "MOTION\nFrames: 1\nFrame Time: 0.1\n" + line + "\n";
  const BvhDocument d = io::parse_bvh(text, "numbers.bvh");
  ASSERT_EQ(d.values.size(), expected.size());
  for (size_t k = 0; k < expected.size(); ++k) EXPECT_EQ(d.values[k], expected[k]) << k;
}

TEST(BvhReader, OneExtraMotionLineIsIgnoredWithAWarning) {
  const std::string head =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
      "MOTION\nFrames: 2\nFrame Time: 0.1\n";
  const BvhDocument d = io::parse_bvh(head + "1 2 3\n4 5 6\n7 8 9\n", "extra.bvh");
  EXPECT_EQ(d.frames, 2);
  EXPECT_EQ(d.values.size(), 6u);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("extra.bvh: line 12"), std::string::npos) << d.warnings[0];
  EXPECT_NE(d.warnings[0].find("ignored"), std::string::npos);
  expect_error([&] { io::parse_bvh(head + "1 2 3\n4 5 6\n7 8 9\n1 1 1\n", "x.bvh"); },
               {"x.bvh: line 13", "goes on past the 2 frames", "line 8"});
}

TEST(BvhReader, SharedBoxingFileDeclaresOneFrameLessThanItHolds) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string path = bvh_data_dir() + "/boxing_toes_zxy.bvh";
  const BvhDocument d = io::parse_bvh(read_file(path), path);
  EXPECT_EQ(d.frames, 3069);
  EXPECT_EQ(d.channels, 66);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_NE(d.warnings[0].find("line 3199"), std::string::npos) << d.warnings[0];
}

TEST(BvhReader, SkeletonsWithoutChannelsStillNeedTheirFrameLines) {
  const std::string head =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 1 0\nCHANNELS 0\nJOINT a\n{\nOFFSET 0 1 0\nCHANNELS 0\n}\n}\n"
      "MOTION\n";
  const BvhDocument d = io::parse_bvh(head + "Frames: 2\nFrame Time: 1\n\n\n", "zero.bvh");
  EXPECT_EQ(d.frames, 2);
  EXPECT_EQ(d.channels, 0);
  {
    fixtures::AllocationCounter allocations;
    expect_error([&] { io::parse_bvh(head + "Frames: 9999999\nFrame Time: 1\n\n", "z.bvh"); },
                 {"z.bvh: line 15", "declares 9999999 frames but the file holds 1 motion lines"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);
  }
  expect_error([&] { io::parse_bvh(head + "Frames: 1\nFrame Time: 1\n1\n", "z.bvh"); },
               {"z.bvh: line 15", "frame 1 has 1 values, expected 0"});
  // a joint without channels is still a joint: spherical, written back with 3 channels
  const BvhImport imp = io::import_bvh(d, "zero.bvh");
  EXPECT_EQ(imp.model->joint_type[imp.model->link_index("a")], core::JointType::kSpherical);
  BvhExportOptions o;
  o.layout = &imp.layout;
  const BvhDocument back = io::parse_bvh(io::write_bvh(*imp.model, imp.clip, o), "z");
  EXPECT_EQ(joint_names(back), (std::vector<std::string>{"r", "a"}));
  EXPECT_EQ(back.frames, 2);
}

// every file of the malformed corpus: the file name, the line and the rule
TEST(BvhReader, MalformedCorpusFailsWithFileLineAndRule) {
  struct Case {
    const char* file;
    int line;  // 0: no line to name
    const char* fragment;
  };
  const Case cases[] = {
      {"wrong_value_count.bvh", 20, "frame 2 has 8 values, expected 9"},
      {"too_many_values.bvh", 20, "frame 2 has 10 values, expected 9"},
      {"frames_larger_than_data.bvh", 20, "declares 5 frames but the file holds 2 motion lines"},
      {"nan_value.bvh", 20, "'nan' is not finite"},
      {"inf_value.bvh", 20, "'-inf' is not finite"},
      {"huge_value.bvh", 19, "exceeds 1e+09 in magnitude"},
      {"not_a_number.bvh", 19, "'1.2.3' is not a number"},
      {"billion_frames.bvh", 17, "exceeds the limit of 10000000 frames (rule: kMaxBvhFrames)"},
      {"frames_not_a_number.bvh", 17, "is not a frame count"},
      {"negative_frame_time.bvh", 18, "Frame Time '-0.1' is not in (0, 3600]"},
      {"nan_frame_time.bvh", 18, "is not finite"},
      {"two_extra_lines.bvh", 21, "goes on past the 1 frames"},
      {"missing_root.bvh", 2, "missing ROOT"},
      {"missing_hierarchy.bvh", 1, "expected HIERARCHY, found 'ROOT'"},
      {"empty.bvh", 1, "the file is empty"},
      {"duplicate_names.bvh", 6, "joint name 'Hips' is already used on line 2"},
      {"unknown_channel.bvh", 9, "unknown channel 'Wrotation'"},
      {"channels_count_too_large.bvh", 10, "declares 4 channels but lists 3"},
      {"channels_count_too_small.bvh", 9, "declares 2 channels but lists more"},
      {"channels_count_over_six.bvh", 9, "'7' is not a channel count"},
      {"duplicate_channel.bvh", 9, "channel Zrotation appears twice"},
      {"two_roots.bvh", 16, "a second ROOT"},
      {"truncated_hierarchy.bvh", 10, "the file ends inside joint 'Spine' (line 6)"},
      {"truncated_motion.bvh", 21, "frame 3 has 5 values, expected 9"},
      {"missing_motion.bvh", 16, "missing MOTION section"},
      {"missing_offset.bvh", 9, "joint 'Spine' (line 6) needs OFFSET and CHANNELS"},
      {"offset_two_numbers.bvh", 9, "has 2 numbers (rule: OFFSET x y z)"},
      {"end_site_with_channels.bvh", 13, "has CHANNELS (rule: an End Site has only an OFFSET)"},
      {"nan_offset.bvh", 8, "'nan' is not finite"},
      {"unnamed_joint.bvh", 6, "JOINT without a name"},
      {"unclosed_root.bvh", 15, "MOTION inside ROOT 'Hips' (line 2)"},
      {"binary_garbage.bvh", 1,
       "is a control character (rule: a BVH hierarchy is text; binary data?)"},
      {"binary_in_hierarchy.bvh", 6, "'\\x00' is a control character"},
      {"binary_in_motion.bvh", 20, "'\\x00\\xff\\xfe\\x01' is not a number"},
  };
  std::set<std::string> covered;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const std::string path = malformed_dir() + "/" + c.file;
    ASSERT_TRUE(fs::exists(path));
    covered.insert(c.file);
    const std::string where = path + ": line " + std::to_string(c.line) + ": ";
    expect_error([&] { io::load_bvh_file(path); }, {where, c.fragment});
  }
  // every file in the folder has a case
  for (const auto& e : fs::directory_iterator(malformed_dir())) {
    EXPECT_TRUE(covered.count(e.path().filename().string())) << e.path() << " has no case";
  }
}

TEST(BvhReader, HugeHeadersAllocateNothingTheDataDoesNotHold) {
  const std::string head =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Xrotation "
      "Yrotation Zrotation\n}\nMOTION\n";
  const std::string two = "Frame Time: 0.1\n1 2 3 4 5 6\n1 2 3 4 5 6\n";
  {
    const std::string text = head + "Frames: 1000000000\n" + two;
    fixtures::AllocationCounter allocations;
    expect_error([&] { io::parse_bvh(text, "big.bvh"); }, {"big.bvh: line 8", "kMaxBvhFrames"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);
  }
  {
    // under the frame limit: 10 million frames × 6 values would be 480 MB; the data holds 2
    const std::string text = head + "Frames: 9999999\n" + two;
    fixtures::AllocationCounter allocations;
    expect_error([&] { io::parse_bvh(text, "big.bvh"); },
                 {"big.bvh: line 11", "declares 9999999 frames but the file holds 2 motion lines"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);
  }
}

// A clip budget (io/clip_budget.hpp) is checked when the header is read: a file over it is
// refused naming the limit and its setting, before one frame is stored.
TEST(BvhReader, AClipOverTheBudgetIsRefusedAtItsHeader) {
  const std::string head =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n"
      "JOINT a\n{\nOFFSET 0 1 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n}\nMOTION\n";
  std::string frames;
  for (int f = 0; f < 200'000; ++f) frames += "1 2 3 4 5 6\n";
  const std::string text = head + "Frames: 200000\nFrame Time: 0.01\n" + frames;
  io::ClipBudget budget;
  budget.max_frames = 1000;
  budget.frames_setting = "--max-clip-frames";
  {
    fixtures::AllocationCounter allocations;
    expect_error([&] { io::parse_bvh(text, "long.bvh", budget); },
                 {"long.bvh: line 13: Frames: 200000 at Frame Time 0.01 s",
                  "200000 frames exceed the limit of 1000 frames per clip (set by "
                  "--max-clip-frames)"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);  // the 200000 frames were never stored
  }
  // the length: 199999 × 0.01 s
  budget = io::ClipBudget{};
  budget.max_seconds = 60;
  expect_error([&] { io::parse_bvh(text, "long.bvh", budget); },
               {"1999.99 s exceed the limit of 60 s per clip"});
  // the numbers: per frame the larger of the file's 6 values and the imported 7 + 4 coordinates
  budget = io::ClipBudget{};
  budget.max_values = 11 * 199'999;
  budget.values_setting = "--max-clip-values";
  expect_error([&] { io::parse_bvh(text, "long.bvh", budget); },
               {"200000 frames × 11 numbers = 2200000 numbers exceed the limit of 2199989",
                "(set by --max-clip-values)"});
  budget.max_values = 11 * 200'000;
  EXPECT_EQ(io::parse_bvh(text, "long.bvh", budget).frames, 200'000);  // exactly the limit
  // load_bvh_string passes its options' budget to the reader
  io::BvhImportOptions options;
  options.budget.max_frames = 10;
  expect_error([&] { io::load_bvh_string(text, "long.bvh", options); }, {"limit of 10 frames"});
}

TEST(BvhReader, TenMegabyteLinesAreRefusedWithoutCopying) {
  const std::string big(10 << 20, '7');
  const std::string head =
      "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Xrotation Yrotation Zrotation\n}\n"
      "MOTION\nFrames: 1\nFrame Time: 0.1\n";
  {
    const std::string text = "HIERARCHY\nROOT " + big + "\n{\n";
    fixtures::AllocationCounter allocations;
    expect_error(
        [&] { io::parse_bvh(text, "long.bvh"); },
        {"long.bvh: line 2: the line is longer than 1048576 bytes (rule: kMaxBvhLineBytes)"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);
  }
  {
    const std::string text = head + "1 2 " + big + "\n";
    fixtures::AllocationCounter allocations;
    expect_error([&] { io::parse_bvh(text, "long.bvh"); },
                 {"long.bvh: line 10: the line is longer than 1048576 bytes"});
    EXPECT_LT(allocations.bytes(), 64 * 1024);
  }
  {
    // a 10 MB file of one motion line per frame is fine, as long as every line is short
    std::string text = head;
    text.replace(text.find("Frames: 1"), 9, "Frames: 600000");
    for (int k = 0; k < 600000; ++k) text += "1.5 -2.25 3\n";
    const BvhDocument d = io::parse_bvh(text, "many.bvh");
    EXPECT_EQ(d.frames, 600000);
    EXPECT_EQ(d.values.back(), 3.0);
  }
}

TEST(BvhReader, FileLevelLimitsAndMissingFiles) {
  TempDir dir;
  expect_error([&] { io::load_bvh_file(dir.file("absent.bvh")); },
               {"absent.bvh: cannot open the file"});
  expect_error([&] { io::load_bvh_file(dir.path.string()); }, {"is a directory"});
  // a sparse file larger than kMaxBvhBytes is refused from its size, without reading it
  const std::string big = dir.file("big.bvh");
  { std::ofstream(big) << "HIERARCHY"; }
  fs::resize_file(big, io::kMaxBvhBytes + 1);
  expect_error([&] { io::load_bvh_file(big); },
               {"big.bvh: file is 268435457 bytes", "a BVH file is at most 268435456 bytes"});
}

// ---------------------------------------------------------------------------------------------
// import

TEST(BvhImport, BuildsTheSkeletonAsAModel) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string path = bvh_data_dir() + "/cmu_walk_cgspeed.bvh";
  const BvhImport imp = io::load_bvh_file(path);
  const core::Model& m = *imp.model;
  EXPECT_EQ(m.name, "cmu_walk_cgspeed");
  EXPECT_EQ(m.nlinks(), 31 + 7);
  EXPECT_EQ(m.joint_type[1], core::JointType::kFree);
  EXPECT_EQ(m.link_name[1], "Hips");
  int spherical = 0, fixed = 0;
  for (int i = 2; i < m.njoints; ++i) {
    if (m.joint_type[i] == core::JointType::kSpherical) ++spherical;
    if (m.joint_type[i] == core::JointType::kFixed) ++fixed;
    EXPECT_TRUE(m.X_PJ[i].R.isIdentity(0));
  }
  EXPECT_EQ(spherical, 30);
  EXPECT_EQ(fixed, 7);
  const int head_end = m.link_index("Head_end");
  ASSERT_GT(head_end, 0);
  EXPECT_EQ(m.link_name[m.parent[head_end]], "Head");
  EXPECT_EQ(m.joint_type[head_end], core::JointType::kFixed);
  // CMU units: 1/0.45 inch
  EXPECT_EQ(imp.unit, "CMU units (1/0.45 inch)");
  EXPECT_DOUBLE_EQ(imp.layout.scale, 2.54 / 45.0);
  EXPECT_GT(imp.height, 1.2);
  EXPECT_LT(imp.height, 2.0);
  EXPECT_NEAR(m.total_mass(), 70.0, 1e-9);
  // masses follow the bone lengths: a thigh outweighs a finger, End Sites weigh nothing
  EXPECT_GT(m.inertia[m.link_index("LeftUpLeg")].mass,
            m.inertia[m.link_index("LeftFingerBase")].mass);
  EXPECT_EQ(m.inertia[head_end].mass, 0.0);
  // capsules for the collision shapes
  EXPECT_EQ(m.collision[m.link_index("LeftUpLeg")].size(), 1u);
  EXPECT_EQ(m.collision[m.link_index("LeftUpLeg")][0].shape, core::Geometry::Shape::kCapsule);
  // the clip: 344 frames at 120 Hz, valid configurations
  EXPECT_EQ(imp.clip.size(), 344);
  EXPECT_DOUBLE_EQ(imp.clip.frame_time, 0.0083333);
  EXPECT_EQ(core::check_clip(m, imp.clip), "");
  // the layout names the file's joints with their channels
  ASSERT_EQ(imp.layout.joints.size(), 31u);
  EXPECT_EQ(imp.layout.joints[0].channels.size(), 6u);
  EXPECT_EQ(io::to_string(imp.layout.joints[1].channels[0]), std::string("Zrotation"));
  // total mass and scale options
  BvhImportOptions o;
  o.total_mass = 55;
  o.scale = 0.01;
  const BvhImport b = io::load_bvh_file(path, o);
  EXPECT_NEAR(b.model->total_mass(), 55.0, 1e-9);
  EXPECT_EQ(b.unit, "option");
  EXPECT_NEAR(b.height, imp.height / (2.54 / 45.0) * 0.01, 1e-12);
  o.scale = -1;
  expect_error([&] { io::load_bvh_file(path, o); }, {"scale -1 is not a positive"});
}

TEST(BvhImport, ModelPosesEqualTheFilesOwnForwardKinematics) {
  PINDRAG_REQUIRE_DATA_DIR();
  for (const std::string& path : shared_files()) {
    SCOPED_TRACE(path);
    const BvhDocument doc = io::parse_bvh(read_file(path), path);
    const BvhImport imp = io::import_bvh(doc, path);
    const double s = imp.layout.scale;
    core::Data data(*imp.model);
    double worst = 0, worst_rot = 0;
    for (int f = 0; f < doc.frames; f += std::max(1, doc.frames / 40)) {
      const auto X = io::bvh_world_poses(doc, f);
      core::forward_kinematics(*imp.model, data, imp.clip.frames[f]);
      for (size_t k = 0; k < doc.nodes.size(); ++k) {
        worst = std::max(worst, (X[k].p * s - data.X_W[imp.node_link[k]].p).norm());
        worst_rot = std::max(worst_rot, geodesic(X[k].R, data.X_W[imp.node_link[k]].R));
      }
    }
    EXPECT_LT(worst, 1e-9 * std::max(1.0, imp.height));
    EXPECT_LT(worst_rot, 1e-9);
  }
}

TEST(BvhImport, AutomaticScalePerSharedFile) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::map<std::string, double> expected = {{"boxing_toes_zxy.bvh", 0.01},
                                                  {"cmu_01_01_jumps.bvh", 2.54 / 45},
                                                  {"cmu_131_01_mj_walk_3dsmax.bvh", 2.54 / 45},
                                                  {"cmu_walk_cgspeed.bvh", 2.54 / 45},
                                                  {"fairmotion_sinusoidal_xyz.bvh", 2.54 / 45},
                                                  {"mixamo_naming_freebvh.bvh", 0.01},
                                                  {"optitrack_arena_louise.bvh", 0.01},
                                                  {"pfnn_hierarchy_metres.bvh", 1.0}};
  for (const std::string& path : shared_files()) {
    const std::string name = fs::path(path).filename().string();
    const BvhDocument doc = io::parse_bvh(read_file(path), path);
    const io::BvhUnit u = io::bvh_auto_scale(doc);
    ASSERT_TRUE(expected.count(name)) << name;
    EXPECT_DOUBLE_EQ(u.scale, expected.at(name)) << name << ": " << u.unit;
    const double height = io::bvh_rest_extent(doc).height * u.scale;
    std::printf("  %-32s unit %-24s rest height %.3f m\n", name.c_str(), u.unit.c_str(), height);
  }
}

// Every link with mass has rotational inertia and a collision shape; every shape has an
// orthonormal pose; a capsule lies along its bone: its axis (+Z of the shape frame) points from
// the joint to the shape's centre, and it is twice that long.
void expect_capsules_along_their_bones(const core::Model& m) {
  for (int i = 1; i < m.njoints; ++i) {
    if (m.inertia[i].mass > 0) {
      EXPECT_GT(m.inertia[i].inertia_about_com().trace(), 0) << m.link_name[i];
      EXPECT_FALSE(m.collision[i].empty()) << m.link_name[i];
    }
    for (const core::Geometry& g : m.collision[i]) {
      const Matrix3& R = g.X_LinkShape.R;
      EXPECT_LT((R.transpose() * R - Matrix3::Identity()).norm(), 1e-12) << m.link_name[i];
      EXPECT_GT(R.determinant(), 0) << m.link_name[i];
      EXPECT_GT(g.radius, 0) << m.link_name[i];
      if (g.shape != core::Geometry::Shape::kCapsule) continue;
      const Vector3& p = g.X_LinkShape.p;
      const Vector3 u = (p / p.cwiseAbs().maxCoeff()).normalized();
      EXPECT_LT((R.col(2) - u).norm(), 1e-9) << m.link_name[i];
      EXPECT_NEAR(g.length, 2 * p.stableNorm(), 1e-12 * g.length) << m.link_name[i];
    }
  }
}

// A hips joint with one bone to an End Site at `offset`, next to an ordinary leg.
std::string one_bone(const std::string& offset) {
  return "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n"
         "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
         "\tJOINT Bone\n\t{\n\t\tOFFSET 0 10 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
         "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET " +
         offset +
         "\n\t\t}\n\t}\n"
         "\tJOINT Leg\n\t{\n\t\tOFFSET 9 -5 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
         "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 -40 0\n\t\t}\n\t}\n}\n"
         "MOTION\nFrames: 1\nFrame Time: 0.04\n0 90 0 0 0 0 10 20 30 -10 5 0\n";
}

// The fuzzer's find: an OFFSET of -1e6 next to offsets of ~10 put a capsule within 1e-5 rad of
// -Z, where Eigen's FromTwoVectors returns a quaternion 1e-6 off unit length, and the model
// builder refused the capsule's rotation as not orthonormal.
TEST(BvhImport, AnOffsetFarBeyondItsSiblingsImports) {
  const std::string path =
      fixtures::source_dir() + "/tests/fixtures/bvh/offset_far_beyond_its_siblings.bvh";
  const BvhImport imp = io::load_bvh_file(path);
  const core::Model& m = *imp.model;
  expect_capsules_along_their_bones(m);
  EXPECT_NEAR(m.total_mass(), 70.0, 1e-9);
  EXPECT_EQ(core::check_clip(m, imp.clip), "");
  // Hips' bone to Spine points (almost exactly) along -Z
  const int hips = m.link_index("Hips");
  ASSERT_GE(hips, 1);
  const auto& shapes = m.collision[hips];
  ASSERT_EQ(shapes.size(), 2u);
  EXPECT_LT((shapes[0].X_LinkShape.R.col(2) - Vector3(0, 1e-5, -1)).norm(), 1e-9);
}

// Any document the reader accepts imports: offsets up to kMaxBvhMagnitude, bones antiparallel to
// the capsule axis, exactly along -Y, shorter than a denormal, and a skeleton of 1e-300 units.
TEST(BvhImport, ExtremeOffsetsGiveValidShapes) {
  for (const std::string offset :
       {"0 0 1000000000", "0 0 -1000000000", "-1e9 1e9 -1e9", "0 -7 0", "0 0 -7", "0 0.01 -1000",
        "1e-300 0 -7", "0 1e-300 0", "4.9e-324 0 0", "0 0 0"}) {
    SCOPED_TRACE(offset);
    const BvhImport imp = io::load_bvh_string(one_bone(offset), "extreme.bvh");
    expect_capsules_along_their_bones(*imp.model);
    EXPECT_NEAR(imp.model->total_mass(), 70.0, 1e-9);
    EXPECT_EQ(core::check_clip(*imp.model, imp.clip), "");
  }
  // a bone exactly along -Y turns the capsule's +Z onto -Y
  const BvhImport down = io::load_bvh_string(one_bone("0 -7 0"), "down.bvh");
  const auto& bone = down.model->collision[down.model->link_index("Bone")];
  ASSERT_EQ(bone.size(), 1u);
  EXPECT_LT((bone[0].X_LinkShape.R.col(2) - Vector3(0, -1, 0)).norm(), 1e-15);
  // two bones too short for a capsule (4e-8 units, under 1e-9 of the 55-unit figure) but longer
  // together: a sphere, not a link of mass without inertia
  std::string stubs = one_bone("0 4e-8 0");
  const std::string end = "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 4e-8 0\n\t\t}\n";
  stubs.insert(stubs.find(end) + end.size(), end);
  const BvhImport s = io::load_bvh_string(stubs, "stubs.bvh");
  expect_capsules_along_their_bones(*s.model);
  const auto& stub = s.model->collision[s.model->link_index("Bone")];
  ASSERT_EQ(stub.size(), 1u);
  EXPECT_EQ(stub[0].shape, core::Geometry::Shape::kSphere);
  // a whole skeleton 1e-300 units tall
  std::string tiny = one_bone("0 1e-300 0");
  for (const char* o : {"0 10 0", "9 -5 0", "0 -40 0"}) {
    tiny.replace(tiny.find(o), std::string(o).size(), "0 -1e-300 0");
  }
  const BvhImport t = io::load_bvh_string(tiny, "tiny.bvh");
  expect_capsules_along_their_bones(*t.model);
  EXPECT_NEAR(t.model->total_mass(), 70.0, 1e-9);
  // it counts as a skeleton without extent: 1 m for the radii, so no link has mass without
  // rotational inertia (1e-300² underflows)
  for (int i = 1; i < t.model->njoints; ++i) {
    if (t.model->inertia[i].mass == 0) continue;
    EXPECT_GT(t.model->inertia[i].inertia_about_com().trace(), 1e-6) << t.model->link_name[i];
  }
}

// Ordinary files keep the capsule of the shortest arc from +Z to the bone (what
// Quaternion::FromTwoVectors gives away from -Z).
TEST(BvhImport, CapsulesTakeTheShortestArcFromZ) {
  for (const char* name : {"mixed_orders.bvh", "liberal_crlf.bvh"}) {
    const std::string path = fixtures::source_dir() + "/tests/fixtures/bvh/" + name;
    const BvhImport imp = io::load_bvh_file(path);
    expect_capsules_along_their_bones(*imp.model);
    int capsules = 0;
    for (const auto& shapes : imp.model->collision) {
      for (const core::Geometry& g : shapes) {
        if (g.shape != core::Geometry::Shape::kCapsule) continue;
        const Vector3 u = g.X_LinkShape.p.normalized();
        if (u.z() < -0.999) continue;
        const Matrix3 R = Quaternion::FromTwoVectors(Vector3::UnitZ(), u).toRotationMatrix();
        EXPECT_LT((g.X_LinkShape.R - R).norm(), 1e-12) << name;
        ++capsules;
      }
    }
    EXPECT_GE(capsules, 2) << name;
  }
}

// ---------------------------------------------------------------------------------------------
// the writer

TEST(BvhWriter, WritesTheConservativeForm) {
  const auto m = core::build_human_figure({});
  core::Clip clip;
  clip.frame_time = 1.0 / 120;
  for (int k = 0; k < 3; ++k) clip.frames.push_back(core::random_configuration(*m, 40 + k));
  const std::string text = io::write_bvh(*m, clip);
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "HIERARCHY");
  std::getline(in, line);
  EXPECT_EQ(line, "ROOT pelvis");
  std::getline(in, line);
  EXPECT_EQ(line, "{");
  std::getline(in, line);
  EXPECT_EQ(line, "\tOFFSET 0.000000 0.000000 0.000000");
  std::getline(in, line);
  EXPECT_EQ(line, "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation");
  EXPECT_EQ(text.find('\r'), std::string::npos);
  EXPECT_EQ(text.find("  "), std::string::npos);
  EXPECT_EQ(text.find("-0.000000"), std::string::npos);
  EXPECT_NE(text.find("\nFrame Time: 0.008333333333333333\n"), std::string::npos);
  // every non-root joint 3 channels; every number in fixed notation with 6 decimals
  const std::regex channels3("^\\t+CHANNELS 3 Zrotation Xrotation Yrotation$");
  const std::regex offset(
      "^\\t+OFFSET -?[0-9]+\\.[0-9]{6} -?[0-9]+\\.[0-9]{6} -?[0-9]+\\.[0-9]{6}$");
  const std::regex values("^(-?[0-9]+\\.[0-9]{6})( -?[0-9]+\\.[0-9]{6})*$");
  int joints = 0, end_sites = 0, motion_lines = 0;
  bool motion = false;
  std::istringstream all(text);
  while (std::getline(all, line)) {
    if (line == "MOTION") motion = true;
    if (motion) {
      if (!line.empty() && line[0] != 'M' && line[0] != 'F') {
        EXPECT_TRUE(std::regex_match(line, values)) << line.substr(0, 80);
        ++motion_lines;
      }
      continue;
    }
    if (line.find("JOINT ") != std::string::npos) ++joints;
    if (line.find("End Site") != std::string::npos) ++end_sites;
    if (line.find("CHANNELS 3") != std::string::npos) {
      EXPECT_TRUE(std::regex_match(line, channels3));
    }
    if (line.find("OFFSET") != std::string::npos) {
      EXPECT_TRUE(std::regex_match(line, offset)) << line;
    }
  }
  EXPECT_EQ(joints, m->nlinks() - 1);  // human48 has no fixed joints
  EXPECT_GT(end_sites, 4);             // the leaves: head, hands, toes
  EXPECT_EQ(motion_lines, 3);
}

TEST(BvhWriter, NamesAreSanitizedAndUnique) {
  core::ModelBuilder b("names");
  auto add = [&](const std::string& name, const std::string& parent, core::JointType t) {
    core::LinkSpec l = fixtures::box_link(name, parent, 1.0, Vector3(0.1, 0.1, 0.1));
    l.joint.type = t;
    l.joint.X_PJ.p = Vector3(0, 0.1, 0);
    b.add_link(l);
  };
  add("mixamorig:Hips", "", core::JointType::kFree);
  add("Left Arm.001/[x]", "mixamorig:Hips", core::JointType::kSpherical);
  add("Left_Arm_001__x_", "mixamorig:Hips", core::JointType::kSpherical);
  add("\xc3\xa9paule", "mixamorig:Hips", core::JointType::kSpherical);
  const auto m = b.finalize();
  core::Clip clip;
  clip.frames.push_back(core::neutral_configuration(*m));
  const BvhDocument d = io::parse_bvh(io::write_bvh(*m, clip), "names.bvh");
  EXPECT_EQ(joint_names(d), (std::vector<std::string>{"mixamorig_Hips", "Left_Arm_001__x_",
                                                      "Left_Arm_001__x__2", "__paule"}));
}

TEST(BvhWriter, SavesAtomically) {
  TempDir dir;
  const auto m = core::build_human_figure({});
  core::Clip clip;
  clip.frames.push_back(core::random_configuration(*m, 1));
  const std::string path = dir.file("out.bvh");
  { std::ofstream(path) << "old"; }
  io::save_bvh_file(*m, clip, path);
  EXPECT_EQ(read_file(path), io::write_bvh(*m, clip));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path)) ++entries;
  EXPECT_EQ(entries, 1) << "no temporary file left behind";
  EXPECT_THROW(io::save_bvh_file(*m, clip, dir.file("missing/out.bvh")), std::system_error);
  // a clip that does not fit is refused before anything is written
  core::Clip bad = clip;
  bad.frames[0][3] = std::nan("");
  EXPECT_THROW(io::save_bvh_file(*m, bad, path), std::invalid_argument);
  BvhExportOptions o;
  o.rotation_order = "XXY";
  EXPECT_THROW(io::write_bvh(*m, clip, o), std::invalid_argument);
  o.rotation_order.reset();
  o.scale = 0;
  EXPECT_THROW(io::write_bvh(*m, clip, o), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// round trips

// import, export (as the file was: names, channel orders, units), re-import
struct RoundTrip {
  BvhImport a, b;
  BvhDocument doc_a, doc_b;
  std::string text;
};
RoundTrip round_trip(const std::string& text,
                     const std::string& name,
                     const BvhImportOptions& options = {}) {
  RoundTrip r;
  r.doc_a = io::parse_bvh(text, name);
  r.a = io::import_bvh(r.doc_a, name, options);
  BvhExportOptions o;
  o.layout = &r.a.layout;
  r.text = io::write_bvh(*r.a.model, r.a.clip, o);
  r.doc_b = io::parse_bvh(r.text, name + " (exported)");
  BvhImportOptions same = options;
  same.scale = r.a.layout.scale;
  r.b = io::import_bvh(r.doc_b, name + " (exported)", same);
  return r;
}

void expect_same_header(const RoundTrip& r) {
  std::vector<std::string> expected;
  for (const std::string& n : joint_names(r.doc_a)) expected.push_back(io::sanitize_bvh_name(n));
  EXPECT_EQ(joint_names(r.doc_b), expected);
  EXPECT_EQ(r.doc_b.frames, r.doc_a.frames);
  EXPECT_NEAR(r.doc_b.frame_time, r.doc_a.frame_time, 1e-6 * r.doc_a.frame_time);
  // each joint keeps its rotation order
  for (size_t k = 0; k < r.a.layout.joints.size(); ++k) {
    std::vector<BvhChannel> ra, rb;
    for (BvhChannel c : r.a.layout.joints[k].channels) {
      if (io::is_rotation(c)) ra.push_back(c);
    }
    for (BvhChannel c : r.b.layout.joints[k].channels) {
      if (io::is_rotation(c)) rb.push_back(c);
    }
    if (ra.size() == 3) {
      EXPECT_EQ(ra, rb) << r.a.layout.joints[k].name;
    }
  }
}

TEST(BvhRoundTrip, EverySharedFile) {
  PINDRAG_REQUIRE_DATA_DIR();
  const auto files = shared_files();
  ASSERT_GE(files.size(), 8u);
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    const RoundTrip r = round_trip(read_file(path), path);
    expect_same_header(r);
    const Errors e = compare_nodes(r.a, r.b);
    EXPECT_LT(e.position, 1e-4 * r.a.height);
    EXPECT_LT(e.rotation, 1e-4);
    std::printf(
        "  %-32s %4d frames  height %.3f m  max position error %.3g m (%.3g of the height)"
        "  max rotation error %.3g rad\n",
        fs::path(path).filename().c_str(), r.a.clip.size(), r.a.height, e.position,
        e.position / r.a.height, e.rotation);
    // re-ordered to ZXY and written in metres: every angle is a new decomposition
    BvhExportOptions zxy;
    zxy.layout = &r.a.layout;
    zxy.rotation_order = "ZXY";
    zxy.scale = 1.0;
    BvhImportOptions metres;
    metres.scale = 1.0;
    const BvhImport c = io::load_bvh_string(io::write_bvh(*r.a.model, r.a.clip, zxy),
                                            path + " (ZXY, metres)", metres);
    const Errors ec = compare_nodes(r.a, c);
    EXPECT_LT(ec.position, 1e-4 * r.a.height);
    EXPECT_LT(ec.rotation, 1e-4);
    std::printf(
        "  %-32s as ZXY in metres: max position error %.3g m (%.3g of the height)"
        "  max rotation error %.3g rad\n",
        "", ec.position, ec.position / r.a.height, ec.rotation);
  }
}

// our small valid files (also the fuzzer's seeds): each round-trips
TEST(BvhRoundTrip, ValidFixtures) {
  const std::string dir = fixtures::source_dir() + "/tests/fixtures/bvh";
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    SCOPED_TRACE(e.path());
    ++files;
    const RoundTrip r = round_trip(read_file(e.path().string()), e.path().string());
    expect_same_header(r);
    const Errors err = compare_nodes(r.a, r.b);
    EXPECT_LT(err.position, 1e-4 * std::max(r.a.height, 0.01));
    EXPECT_LT(err.rotation, 1e-4);
  }
  EXPECT_GE(files, 3);
}

// A synthetic skeleton of 24 joints with mixed channel orders (ZXY, ZYX, XYZ, YZX), a 6-channel
// non-root joint, nonzero End Sites, near-gimbal poses and angle jumps across ±180°.
std::string synthetic_bvh(int frames, bool smooth) {
  struct J {
    std::string name;
    int parent;
    Vector3 offset;
    std::string channels;
    Vector3 end;  // End Site offset; zero: none
  };
  const std::string zxy = "Zrotation Xrotation Yrotation", zyx = "Zrotation Yrotation Xrotation",
                    xyz = "Xrotation Yrotation Zrotation", yzx = "Yrotation Zrotation Xrotation";
  std::vector<J> js = {
      {"Hips", -1, {0, 0, 0}, "Xposition Yposition Zposition " + zxy, {}},
      {"Spine", 0, {0, 9, -1}, zxy, {}},
      {"Spine1", 1, {0, 10, 0.5}, zyx, {}},
      {"Neck", 2, {0, 12, 0}, xyz, {}},
      {"Head", 3, {0, 8, 1}, yzx, {0, 15, 2}},
      {"LeftShoulder", 2, {3, 10, 0}, zxy, {}},
      {"LeftArm", 5, {12, 0, 0}, zyx, {}},
      {"LeftForeArm", 6, {25, 0, 0}, xyz, {}},
      {"LeftHand", 7, {22, 0, 0}, yzx, {8, -1, 1}},
      {"RightShoulder", 2, {-3, 10, 0}, zxy, {}},
      {"RightArm", 9, {-12, 0, 0}, zyx, {}},
      {"RightForeArm", 10, {-25, 0, 0}, xyz, {}},
      {"RightHand", 11, {-22, 0, 0}, zxy, {-8, -1, 1}},
      {"LeftUpLeg", 0, {9, -5, 0}, zxy, {}},
      {"LeftLeg", 13, {0, -40, 1}, zyx, {}},
      {"LeftFoot", 14, {0, -42, -2}, xyz, {}},
      {"LeftToe", 15, {0, -5, 12}, yzx, {0, 0, 6}},
      {"RightUpLeg", 0, {-9, -5, 0}, zxy, {}},
      {"RightLeg", 17, {0, -40, 1}, zyx, {}},
      {"RightFoot", 18, {0, -42, -2}, xyz, {}},
      {"RightToe", 19, {0, -5, 12}, zxy, {0, 0, 6}},
      {"Prop", 7, {5, 2, 0}, "Xposition Yposition Zposition " + yzx, {0, 0, 30}},
      {"Tail", 0, {0, -3, -10}, zyx, {}},
      {"TailTip", 22, {0, 0, -15}, xyz, {}},
  };
  // children lists in order
  std::vector<std::vector<int>> kids(js.size());
  for (size_t i = 1; i < js.size(); ++i) kids[js[i].parent].push_back(static_cast<int>(i));
  std::string out = "HIERARCHY\n";
  std::vector<int> order;
  std::function<void(int, int)> emit = [&](int i, int depth) {
    const std::string ind(depth, '\t');
    order.push_back(i);
    const J& j = js[i];
    char buf[128];
    std::snprintf(buf, sizeof buf, "OFFSET %.4f %.4f %.4f", j.offset.x(), j.offset.y(),
                  j.offset.z());
    out +=
        ind + (i == 0 ? "ROOT " : "JOINT ") + j.name + "\n" + ind + "{\n" + ind + "\t" + buf + "\n";
    const int n = static_cast<int>(std::count(j.channels.begin(), j.channels.end(), ' ')) + 1;
    out += ind + "\tCHANNELS " + std::to_string(n) + " " + j.channels + "\n";
    for (int k : kids[i]) emit(k, depth + 1);
    if (j.end.norm() > 0) {
      std::snprintf(buf, sizeof buf, "OFFSET %.4f %.4f %.4f", j.end.x(), j.end.y(), j.end.z());
      out += ind + "\tEnd Site\n" + ind + "\t{\n" + ind + "\t\t" + buf + "\n" + ind + "\t}\n";
    }
    out += ind + "}\n";
  };
  emit(0, 0);
  out += "MOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: 0.0166667\n";
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-180, 180);
  for (int f = 0; f < frames; ++f) {
    std::string line;
    for (int i : order) {
      const J& j = js[i];
      const bool six = j.channels.find("position") != std::string::npos;
      std::vector<double> v;
      if (six) v = {f * 0.5 + (i ? 3 : 0), 90 + 2 * std::sin(f * 0.1), -f * 0.25};
      for (int a = 0; a < 3; ++a) {
        double angle;
        if (smooth) {
          // a slow spin through ±180° on the first axis, gentle swings on the others
          angle = a == 0 ? std::remainder(170 + 4.0 * f + 7 * i, 360.0)
                         : 40 * std::sin(0.07 * f + i + a);
        } else {
          angle = u(rng);
          if (a == 1 && f % 4 == 1) angle = (f % 8 == 1 ? 89.9 : -89.9);  // near gimbal lock
          if (a == 1 && f % 4 == 3) angle = u(rng) / 2;
          if (a == 0 && f % 2 == 1) angle = (i % 2 ? 179.5 : -179.5);  // jumps across ±180°
        }
        v.push_back(angle);
      }
      for (double x : v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.6f ", x);
        line += buf;
      }
    }
    out += line + "\n";
  }
  return out;
}

TEST(BvhRoundTrip, SyntheticMixedOrdersNearGimbalAndWraps) {
  const std::string text = synthetic_bvh(120, false);
  BvhImportOptions o;
  o.scale = 0.01;
  const RoundTrip r = round_trip(text, "synthetic.bvh", o);
  ASSERT_EQ(r.doc_a.joint_count(), 24);
  EXPECT_EQ(r.a.model->joint_type[r.a.model->link_index("Prop")], core::JointType::kFree);
  expect_same_header(r);
  const Errors e = compare_nodes(r.a, r.b);
  EXPECT_LT(e.position, 1e-4 * r.a.height);
  EXPECT_LT(e.rotation, 1e-4);
  std::printf(
      "  synthetic (layout orders): max position error %.3g m (%.3g of the height), "
      "max rotation error %.3g rad\n",
      e.position, e.position / r.a.height, e.rotation);
  // re-ordered: every joint ZXY, XYZ or YXZ, and in metres: the same poses
  for (const char* order : {"ZXY", "XYZ", "YXZ"}) {
    BvhExportOptions x;
    x.layout = &r.a.layout;
    x.rotation_order = order;
    x.scale = 1.0;
    const BvhDocument d = io::parse_bvh(io::write_bvh(*r.a.model, r.a.clip, x), "re.bvh");
    BvhImportOptions metres;
    metres.scale = 1.0;
    const BvhImport c = io::import_bvh(d, "re.bvh", metres);
    const Errors ec = compare_nodes(r.a, c);
    EXPECT_LT(ec.position, 1e-4 * r.a.height) << order;
    EXPECT_LT(ec.rotation, 1e-4) << order;
    std::printf("  synthetic as %s in metres: max position error %.3g m, rotation %.3g rad\n",
                order, ec.position, ec.rotation);
    for (size_t k = 1; k < d.nodes.size(); ++k) {
      if (d.nodes[k].is_end_site()) continue;
      EXPECT_EQ(d.nodes[k].channels.size(), d.nodes[k].name == "Prop" ? 6u : 3u);
      EXPECT_EQ(io::to_string(d.nodes[k].channels.back()), std::string(1, order[2]) + "rotation");
    }
  }
}

TEST(BvhRoundTrip, ExportedAnglesAreContinuous) {
  const std::string text = synthetic_bvh(200, true);
  const RoundTrip r = round_trip(text, "smooth.bvh");
  // the input moves at most 4° per frame per channel (the spin wraps at ±180° in the file); the
  // exported channels move no more than the rotation does, and never jump by 360°
  double step = 0;
  for (int f = 1; f < r.doc_b.frames; ++f) {
    for (const BvhNode& n : r.doc_b.nodes) {
      for (size_t c = 0; c < n.channels.size(); ++c) {
        if (!io::is_rotation(n.channels[c])) continue;
        const int k = n.first_value + static_cast<int>(c);
        step = std::max(step, std::abs(r.doc_b.frame(f)[k] - r.doc_b.frame(f - 1)[k]));
      }
    }
  }
  EXPECT_LT(step, 10.0);
  const Errors e = compare_nodes(r.a, r.b);
  EXPECT_LT(e.position, 1e-4 * r.a.height);
  EXPECT_LT(e.rotation, 1e-4);
}

// our own characters: any Model exports, its links land where they were
TEST(BvhRoundTrip, HumanFiguresAndTheBranchingTree) {
  for (int dof : {48, 34}) {
    core::HumanFigureOptions h;
    h.dof = dof;
    const auto m = core::build_human_figure(h);
    core::Clip clip;
    clip.frame_time = 0.04;
    for (int k = 0; k < 20; ++k) clip.frames.push_back(core::random_configuration(*m, 100 + k));
    const std::string text = io::write_bvh(*m, clip);
    BvhImportOptions metres;
    metres.scale = 1.0;
    const BvhImport b = io::load_bvh_string(text, "human.bvh", metres);
    int compared = 0;
    const Errors e = compare_links_by_name(*m, clip, *b.model, b.clip, &compared);
    const double height = 1.75;
    EXPECT_LT(e.position, 1e-4 * height) << dof;
    EXPECT_LT(e.rotation, 1e-4) << dof;
    int moving = 0;
    for (int i = 1; i < m->njoints; ++i) moving += m->joint_type[i] != core::JointType::kFixed;
    EXPECT_EQ(compared, moving) << "every moving link survives by name";
    std::printf("  human%d: %d links compared, max position error %.3g m, rotation %.3g rad\n", dof,
                compared, e.position, e.rotation);
  }
  // prismatic, rotated placements, fixed links with and without moving children
  const auto tree = fixtures::branching_tree();
  core::Clip clip;
  for (int k = 0; k < 10; ++k) clip.frames.push_back(core::random_configuration(*tree, 7 + k));
  BvhExportOptions o;
  o.rotation_order = "YXZ";
  o.scale = 0.01;
  BvhImportOptions cm;
  cm.scale = 0.01;
  const BvhImport b = io::load_bvh_string(io::write_bvh(*tree, clip, o), "tree.bvh", cm);
  int compared = 0;
  const Errors e = compare_links_by_name(*tree, clip, *b.model, b.clip, &compared);
  EXPECT_LT(e.position, 1e-5);
  EXPECT_LT(e.rotation, 1e-5);
  EXPECT_EQ(compared, 6);  // every link but the fixed hand, which becomes an End Site
  EXPECT_EQ(b.model->joint_type[b.model->link_index("slider")], core::JointType::kFree);
  // the hand's End Site sits where the hand was
  const auto pa = posed(*tree, clip);
  const auto pb = posed(*b.model, b.clip);
  const int hand = tree->link_index("hand"), hand_end = b.model->link_index("hinge_end");
  ASSERT_GT(hand_end, 0);
  for (int f = 0; f < clip.size(); ++f) EXPECT_LT((pa[f][hand].p - pb[f][hand_end].p).norm(), 1e-5);
}

// ---------------------------------------------------------------------------------------------
// independent readers of our exports

std::string web_modules() { return fixtures::source_dir() + "/web/node_modules"; }

// three.js's BVHLoader (Node) reads the exported file: same bones, same world positions as our
// reader gives for that file, every frame
void check_with_threejs(const std::string& bvh_path,
                        const BvhImport& ours,
                        const BvhDocument& doc,
                        double tolerance) {
  const std::string script = fixtures::source_dir() + "/tests/io/bvh_threejs_positions.mjs";
  const auto [status, out] =
      run("node '" + script + "' '" + web_modules() + "' '" + bvh_path + "'");
  ASSERT_EQ(status, 0) << out.substr(0, 400);
  const nlohmann::json j = nlohmann::json::parse(out);
  ASSERT_EQ(j["names"].size(), doc.nodes.size());
  for (size_t k = 0; k < doc.nodes.size(); ++k) {
    EXPECT_EQ(j["names"][k].get<std::string>(),
              doc.nodes[k].is_end_site() ? std::string("ENDSITE") : doc.nodes[k].name);
  }
  ASSERT_EQ(static_cast<int>(j["frames"].size()), ours.clip.size());
  const auto poses = posed(*ours.model, ours.clip);
  const double s = ours.layout.scale;
  double worst = 0;
  for (int f = 0; f < ours.clip.size(); ++f) {
    const auto& row = j["frames"][f];
    for (size_t k = 0; k < doc.nodes.size(); ++k) {
      const Vector3 p(row[3 * k].get<double>(), row[3 * k + 1].get<double>(),
                      row[3 * k + 2].get<double>());
      worst = std::max(worst, (p * s - poses[f][ours.node_link[k]].p).norm());
    }
  }
  EXPECT_LT(worst, tolerance);
  std::printf("  three.js %-40s max position difference %.3g m\n",
              fs::path(bvh_path).filename().c_str(), worst);
}

// assimp's CLI reads the exported file without error, with one node per joint and End Site
void check_with_assimp(const std::string& bvh_path, const BvhDocument& doc) {
  const auto [status, out] = run("assimp info '" + bvh_path + "' 2>&1");
  ASSERT_EQ(status, 0) << out.substr(0, 400);
  EXPECT_EQ(out.find("ERROR"), std::string::npos) << out.substr(0, 400);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("Nodes:\\s+([0-9]+)"))) << out.substr(0, 400);
  EXPECT_EQ(std::stoul(m[1].str()), doc.nodes.size()) << bvh_path;
  // the node tree names every joint, End Sites as EndSite_<joint>, in file order
  const size_t tree = out.find("Node hierarchy:");
  ASSERT_NE(tree, std::string::npos);
  std::istringstream in(out.substr(tree));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  while (std::getline(in, line) && !line.empty()) {
    const size_t mark = line.rfind("\xe2\x95\xb4");  // '╴'
    std::string name = mark == std::string::npos ? line : line.substr(mark + 3);
    if (const size_t sp = name.find(" ("); sp != std::string::npos) name.resize(sp);
    names.push_back(name);
  }
  std::vector<std::string> expected;
  for (const BvhNode& n : doc.nodes) {
    expected.push_back(n.is_end_site() ? "EndSite_" + doc.nodes[n.parent].name : n.name);
  }
  EXPECT_EQ(names, expected);
}

struct Export {
  std::string path;
  BvhImport ours;  // our reader on the exported file
  BvhDocument doc;
};

std::vector<Export> exports_to_check(const TempDir& dir) {
  std::vector<Export> out;
  auto add = [&](const std::string& name, const std::string& text, std::optional<double> scale) {
    Export e;
    e.path = dir.file(name);
    std::ofstream(e.path, std::ios::binary) << text;
    e.doc = io::parse_bvh(text, e.path);
    BvhImportOptions o;
    o.scale = scale;
    e.ours = io::import_bvh(e.doc, e.path, o);
    out.push_back(std::move(e));
  };
  if (!fixtures::data_dir().empty()) {
    for (const std::string& path : shared_files()) {
      const BvhImport a = io::load_bvh_file(path);
      BvhExportOptions o;
      o.layout = &a.layout;
      add("exported_" + fs::path(path).filename().string(), io::write_bvh(*a.model, a.clip, o),
          a.layout.scale);
    }
  }
  const BvhImport syn = io::load_bvh_string(synthetic_bvh(60, false), "synthetic.bvh");
  BvhExportOptions o;
  o.layout = &syn.layout;
  add("exported_synthetic.bvh", io::write_bvh(*syn.model, syn.clip, o), syn.layout.scale);
  const auto human = core::build_human_figure({});
  core::Clip clip;
  for (int k = 0; k < 10; ++k) clip.frames.push_back(core::random_configuration(*human, 300 + k));
  add("exported_human48.bvh", io::write_bvh(*human, clip), 1.0);
  core::HumanFigureOptions h34;
  h34.dof = 34;
  const auto human34 = core::build_human_figure(h34);
  core::Clip clip34;
  for (int k = 0; k < 10; ++k)
    clip34.frames.push_back(core::random_configuration(*human34, 400 + k));
  add("exported_human34.bvh", io::write_bvh(*human34, clip34), 1.0);
  const auto tree = fixtures::branching_tree();
  core::Clip tclip;
  for (int k = 0; k < 10; ++k) tclip.frames.push_back(core::random_configuration(*tree, 500 + k));
  add("exported_tree.bvh", io::write_bvh(*tree, tclip), 1.0);
  return out;
}

TEST(BvhIndependentReaders, ThreeJsBvhLoaderReadsOurExports) {
  if (!on_path("node")) GTEST_SKIP() << "node is not installed; skipping the three.js check";
  if (!fs::exists(web_modules() + "/three/examples/jsm/loaders/BVHLoader.js")) {
    GTEST_SKIP() << web_modules() << "/three is missing (run npm ci in web/); skipping";
  }
  TempDir dir;
  for (const Export& e : exports_to_check(dir)) {
    SCOPED_TRACE(e.path);
    // three.js keeps keyframes in float32: 1e-4 of the height covers its rounding
    const double height = std::max(e.ours.height, 0.1);
    check_with_threejs(e.path, e.ours, e.doc, 1e-4 * height);
  }
}

TEST(BvhIndependentReaders, AssimpReadsOurExports) {
  if (!on_path("assimp")) GTEST_SKIP() << "assimp (assimp-utils) is not installed; skipping";
  TempDir dir;
  for (const Export& e : exports_to_check(dir)) {
    SCOPED_TRACE(e.path);
    check_with_assimp(e.path, e.doc);
  }
}

}  // namespace
