// Tests for `pindrag convert`, `pindrag edit` and `pindrag info` on clips, run as the executable
// (exit status, stdout, stderr) on the shared CMU walk, plus the edit script reader directly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/edit_script.hpp"
#include "cli/json_fields.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/run_pindrag.hpp"
#include "tests/io/gltf_reader.hpp"

namespace {

using nlohmann::json;

using fixtures::Outcome;

// runs `pindrag <args>` with stdout and stderr captured in files of `dir`
Outcome pindrag(const gltf_test::TempDir& dir, const std::string& args) {
  return fixtures::run_pindrag(PINDRAG_EXE, dir.path(""), args);
}

std::string walk() { return fixtures::data_dir() + "/bvh/cmu_walk_cgspeed.bvh"; }

// world positions (metres) of the named joints of a BVH document, every frame
using Positions = std::map<std::string, std::vector<core::Vector3>>;
Positions joint_positions(const io::BvhDocument& doc, double scale) {
  Positions p;
  for (int f = 0; f < doc.frames; ++f) {
    const auto poses = io::bvh_world_poses(doc, f);
    for (std::size_t n = 0; n < doc.nodes.size(); ++n) {
      if (!doc.nodes[n].is_end_site()) p[doc.nodes[n].name].push_back(scale * poses[n].p);
    }
  }
  return p;
}

io::BvhDocument read_bvh(const std::string& path) {
  return io::parse_bvh(fixtures::slurp(path), path);
}

TEST(ConvertCommand, BvhToGlbAndBackKeepsEveryJointsWorldPositions) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const std::string glb = dir.path("walk.glb"), bvh = dir.path("walk.bvh");
  Outcome r = pindrag(dir, "convert " + walk() + " " + glb);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("344 frames"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << "no progress bar when stderr is not a terminal";
  // back through the skinned import (the stick figure carries the skeleton)
  r = pindrag(dir, "convert " + glb + " " + bvh + " --fps 120 --scale 0.01");  // to centimetres
  ASSERT_EQ(r.status, 0) << r.err;
  const io::BvhDocument src = read_bvh(walk()), back = read_bvh(bvh);
  ASSERT_EQ(back.frames, src.frames);
  EXPECT_NEAR(back.frame_time, src.frame_time, 1e-6);
  const Positions a = joint_positions(src, io::kCmuUnit), b = joint_positions(back, 0.01);
  const double height = io::bvh_rest_extent(src).height * io::kCmuUnit;
  double worst = 0;
  for (const auto& [name, track] : a) {
    const auto it = b.find(name);
    ASSERT_NE(it, b.end()) << name;
    for (int f = 0; f < src.frames; ++f) worst = std::max(worst, (track[f] - it->second[f]).norm());
  }
  EXPECT_LT(worst, 1e-4 * height) << "worst joint position error " << worst << " m";
}

TEST(ConvertCommand, BvhToBvhWithOrderAndRate) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const std::string out = dir.path("walk_xyz.bvh");
  const Outcome r = pindrag(dir, "convert " + walk() + " " + out + " --order XYZ --fps 60");
  ASSERT_EQ(r.status, 0) << r.err;
  const io::BvhDocument src = read_bvh(walk()), got = read_bvh(out);
  EXPECT_EQ(got.frames, 172);  // 343 frames of 1/120 s = 2.858 s → frames 0..171 at 60 fps
  EXPECT_NEAR(got.frame_time, 1.0 / 60, 1e-9);
  for (const auto& n : got.nodes) {
    if (n.is_end_site()) continue;
    const std::size_t r0 = n.channels.size() - 3;
    EXPECT_EQ(n.channels[r0], io::BvhChannel::kXrotation) << n.name;
    EXPECT_EQ(n.channels[r0 + 2], io::BvhChannel::kZrotation) << n.name;
  }
  // output frame f is source frame 2f (up to the file's frame time .0083333 not being exactly
  // 1/120 s: at most 11 µs apart): the round-trip tolerance, 1e-4 × height, in the same unit
  const Positions a = joint_positions(src, io::kCmuUnit), b = joint_positions(got, io::kCmuUnit);
  const double height = io::bvh_rest_extent(src).height * io::kCmuUnit;
  double worst = 0;
  for (const auto& [name, track] : b) {
    for (int f = 0; f < got.frames; ++f)
      worst = std::max(worst, (track[f] - a.at(name)[2 * f]).norm());
  }
  EXPECT_LT(worst, 1e-4 * height) << "worst joint position error " << worst << " m";
}

// rotation channels of every joint, e.g. "ZXY"
std::vector<std::string> orders(const io::BvhDocument& doc) {
  std::vector<std::string> out;
  for (const io::BvhNode& node : doc.nodes) {
    if (node.is_end_site()) continue;
    std::string order;
    for (io::BvhChannel c : node.channels) {
      if (io::is_rotation(c)) order += static_cast<char>('X' + io::channel_axis(c));
    }
    out.push_back(order);
  }
  return out;
}

TEST(ConvertCommand, BvhToBvhKeepsTheSourceUnitAndOrdersUnlessAsked) {
  gltf_test::TempDir dir;
  const std::string in = dir.path("cm.bvh");
  std::ofstream(in) << "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n"
                       "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                       "JOINT Chest\n{\nOFFSET 0 85.5 -1.25\n"
                       "CHANNELS 3 Zrotation Yrotation Xrotation\n"
                       "End Site\n{\nOFFSET 0 80.25 0\n}\n}\n}\nMOTION\nFrames: 2\n"
                       "Frame Time: 0.01\n1.5 90 2 10 20 30 40 -50 60\n2 91 3 11 21 31 41 -51 61\n";
  const io::BvhDocument src = read_bvh(in);
  // default and "source": centimetres, each joint's order, the same values
  for (const std::string options : {"", " --units source --order source"}) {
    const std::string out = dir.path("same.bvh");
    const Outcome r = pindrag(dir, "convert " + in + " " + out + options + " --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
    const io::BvhDocument got = read_bvh(out);
    EXPECT_EQ(orders(got), (std::vector<std::string>{"ZXY", "ZYX"})) << options;
    ASSERT_EQ(got.nodes.size(), src.nodes.size());
    for (std::size_t k = 0; k < got.nodes.size(); ++k) {
      EXPECT_TRUE(got.nodes[k].offset.isApprox(src.nodes[k].offset, 1e-9)) << options;
    }
    ASSERT_EQ(got.values.size(), src.values.size());
    for (std::size_t k = 0; k < got.values.size(); ++k) {
      EXPECT_NEAR(got.values[k], src.values[k], 1e-6) << options;
    }
  }
  // asked: metres, XYZ on every joint
  const std::string out = dir.path("m_xyz.bvh");
  const Outcome r = pindrag(dir, "convert " + in + " " + out + " --units m --order xyz --quiet");
  ASSERT_EQ(r.status, 0) << r.err;
  const io::BvhDocument got = read_bvh(out);
  EXPECT_EQ(orders(got), (std::vector<std::string>{"XYZ", "XYZ"}));
  EXPECT_NEAR(got.nodes[1].offset.y(), 0.855, 1e-9);
  EXPECT_NEAR(got.frame(1)[1], 0.91, 1e-9);
  // --units and --scale both setting the unit of a BVH written from glTF is refused
  const std::string glb = dir.path("cm.glb");
  ASSERT_EQ(pindrag(dir, "convert " + in + " " + glb + " --quiet").status, 0);
  const Outcome both =
      pindrag(dir, "convert " + glb + " " + dir.path("b.bvh") + " --units cm --scale 0.01");
  EXPECT_NE(both.status, 0);
  EXPECT_NE(both.err.find("--units: not with --scale"), std::string::npos) << both.err;
}

TEST(ConvertCommand, BadInputsExitNonZeroNamingTheProblem) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const std::string out = dir.path("out.bvh");
  struct Case {
    std::string args, expected;
  };
  const std::vector<Case> cases = {
      {"convert " + walk() + " " + dir.path("out.txt"), "OUT: "},
      {"convert " + walk() + " " + out + " --order XXY",
       "--order: 'XXY' (rule: one of XYZ, XZY, YXZ, YZX, ZXY, ZYX, source)"},
      {"convert " + walk() + " " + out + " --units ft",
       "--units: 'ft' (rule: one of m, cm, source)"},
      {"convert " + walk() + " " + dir.path("o.glb") + " --units cm",
       "--units: applies to a BVH output only"},
      {"convert " + walk() + " " + dir.path("o.glb") + " --order ZXY",
       "--order: applies to a BVH output only"},
      {"convert " + walk() + " " + out + " --scale -1", "--scale: must be a positive number"},
      {"convert " + walk() + " " + out + " --fps 0", "--fps must be a number in (0, 1000]"},
      {"convert " + dir.path("missing.bvh") + " " + out, "missing.bvh"},
      {"convert " + fixtures::source_dir() + "/tests/fixtures/malformed/bvh/nan_value.bvh " + out,
       "nan_value.bvh: line"},
  };
  for (const Case& c : cases) {
    const Outcome r = pindrag(dir, c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
  }
}

TEST(InfoCommand, ClipFilesReportFramesTimingAndJoints) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const Outcome r = pindrag(dir, "info " + walk());
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j.at("name"), "cmu_walk_cgspeed");
  EXPECT_EQ(j.at("clip").at("frames"), 344);
  EXPECT_NEAR(j.at("clip").at("frame_time").get<double>(), 0.0083333, 1e-12);
  EXPECT_NEAR(j.at("clip").at("duration").get<double>(), 343 * 0.0083333, 1e-9);
  EXPECT_EQ(j.at("clip").at("joints"), 31);
  EXPECT_EQ(j.at("links"), 31 + 7);  // and 7 End Sites
  // which way it faces where the clip starts, and from which links (the page turns it to +Z)
  EXPECT_LT(std::abs(j.at("facing").at("degrees_from_plus_z").get<double>()), 5.0);
  EXPECT_EQ(j.at("facing").at("from")[0], json({"LeftUpLeg", "RightUpLeg"}));
  EXPECT_EQ(j.at("facing").at("by"), "left and right");
  const Outcome boxing = pindrag(dir, "info " + fixtures::data_dir() + "/bvh/boxing_toes_zxy.bvh");
  ASSERT_EQ(boxing.status, 0) << boxing.err;
  EXPECT_GT(std::abs(json::parse(boxing.out).at("facing").at("degrees_from_plus_z").get<double>()),
            170.0);
  // a skinned glTF: its first animation and its mesh
  const Outcome g = pindrag(dir, "info " + fixtures::data_dir() + "/gltf/CesiumMan.glb");
  ASSERT_EQ(g.status, 0) << g.err;
  const json k = json::parse(g.out);
  EXPECT_GT(k.at("clip").at("frames").get<int>(), 1);
  EXPECT_GT(k.at("clip").at("skin").at("vertices").get<int>(), 0);
  // its bones are named nodes[N]: its toes tell it faces +X
  EXPECT_EQ(k.at("facing").at("by"), "toes");
  EXPECT_NEAR(k.at("facing").at("degrees_from_plus_z").get<double>(), 90.0, 5.0);
  // a bundled character still prints its summary, without a clip
  const Outcome h = pindrag(dir, "info human48");
  ASSERT_EQ(h.status, 0) << h.err;
  EXPECT_FALSE(json::parse(h.out).contains("clip"));
  EXPECT_NEAR(json::parse(h.out).at("facing").at("degrees_from_plus_z").get<double>(), 0.0, 1e-9);
  const Outcome bad = pindrag(dir, "info " + dir.path("nothing.bvh"));
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.err.find("nothing.bvh"), std::string::npos) << bad.err;
}

TEST(InfoCommand, AFileOfAnotherKindIsRefusedNamingEveryKindItReads) {
  gltf_test::TempDir dir;
  {
    std::ofstream f(dir.path("duck.zae"), std::ios::binary);
    f << "PK";
  }
  const Outcome zae = pindrag(dir, "info " + dir.path("duck.zae"));
  EXPECT_EQ(zae.status, 1);
  EXPECT_NE(zae.err.find(dir.path("duck.zae") +
                         ": unknown file type '.zae' (rule: pindrag info "
                         "reads .urdf and .json characters, .bvh, .gltf, .glb, .fbx and .dae "
                         "clips, .c3d marker trials"),
            std::string::npos)
      << zae.err;
}

TEST(InfoCommand, MarkerTrialsReportTimingUnitsAndMissingSamplesPerLabel) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const Outcome r = pindrag(dir, "info " + fixtures::data_dir() + "/c3d/opensim_walking5.c3d");
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  // the trial as the data folder's README describes it: 40 points at 250 Hz, 1103 frames, mm,
  // 45 % of the samples missing
  EXPECT_EQ(j.at("frames"), 1103);
  EXPECT_EQ(j.at("points"), 40);
  EXPECT_EQ(j.at("rate_hz"), 250.0);
  EXPECT_EQ(j.at("units"), "mm");
  EXPECT_NEAR(j.at("missing_fraction").get<double>(), 0.455, 0.005);
  ASSERT_EQ(j.at("labels").size(), 40u);
  double sum = 0;
  for (const auto& [label, v] : j.at("labels").items()) sum += v.at("missing").get<double>();
  EXPECT_NEAR(sum / 40, j.at("missing_fraction").get<double>(), 1e-12);
  // the subject prefix is reported once, the labels without it
  const Outcome c = pindrag(dir, "info " + fixtures::data_dir() + "/c3d/cmu_85_02.c3d");
  ASSERT_EQ(c.status, 0) << c.err;
  const json k = json::parse(c.out);
  EXPECT_EQ(k.at("subject"), "Male");
  EXPECT_TRUE(k.at("labels").contains("LFWT"));
  EXPECT_EQ(k.at("labels").at("LFWT").at("missing"), 0.0);
  // a truncated file is refused with the field named
  {
    std::ofstream f(dir.path("short.c3d"), std::ios::binary);
    f << std::string(100, 'x');
  }
  const Outcome bad = pindrag(dir, "info " + dir.path("short.c3d"));
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.err.find("short.c3d: header"), std::string::npos) << bad.err;
}

// both feet pinned while the right hand is pulled up and forward over half a second
json walk_script() {
  return {
      {"falloff", 0.1},
      {"edits",
       {{{"start", 0.8},
         {"end", 1.3},
         {"pins",
          {{{"link", "LeftFoot"}, {"mode", "pose"}}, {{"link", "RightFoot"}, {"mode", "pose"}}}},
         {"drag",
          {{"link", "RightHand"},
           {"keys",
            {{{"time", 0.8}, {"position", {0, 0, 0}}},
             {{"time", 1.0}, {"position", {0, 0.08, 0.09}}}}}}}}}}};
}

TEST(EditCommand, EditsInMotionKeepingFeetAndOtherFrames) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const std::string script = dir.path("edits.json"), edited = dir.path("edited.bvh"),
                    plain = dir.path("plain.bvh");
  std::ofstream(script) << walk_script().dump(2);
  Outcome r = pindrag(dir, "edit " + walk() + " --script " + script + " -o " + edited);
  ASSERT_EQ(r.status, 0) << r.err;
  r = pindrag(dir, "convert " + walk() + " " + plain);
  ASSERT_EQ(r.status, 0) << r.err;
  const io::BvhDocument a = read_bvh(plain), b = read_bvh(edited);
  ASSERT_EQ(a.frames, b.frames);
  const Positions pa = joint_positions(a, io::kCmuUnit), pb = joint_positions(b, io::kCmuUnit);
  const int first = 96, last = 156, falloff = 12;  // 0.8 s, 1.3 s and 0.1 s at 120 fps
  double foot = 0, hand = 0;
  for (int f = 0; f < a.frames; ++f) {
    const bool same = std::equal(a.frame(f), a.frame(f) + a.channels, b.frame(f));
    if (f < first + 1 - falloff || f > last + falloff) {
      EXPECT_TRUE(same) << "frame " << f;
    }
    if (f > first && f <= last) {
      for (const char* n : {"LeftFoot", "RightFoot"})
        foot = std::max(foot, (pa.at(n)[f] - pb.at(n)[f]).norm());
    }
    if (f >= 120 && f <= last)
      hand = std::max(hand, (pa.at("RightHand")[f] - pb.at("RightHand")[f]).norm());
  }
  EXPECT_LE(foot, 1e-3) << "feet drift in metres";
  EXPECT_GT(hand, 0.1) << "the hand follows the drag 12 cm off the clip";
}

TEST(EditCommand, BadScriptsExitNonZeroNamingTheField) {
  PINDRAG_REQUIRE_DATA_DIR();
  gltf_test::TempDir dir;
  const std::string script = dir.path("edits.json"), out = dir.path("out.bvh");
  auto expect_refused = [&](const json& s, const std::string& field) {
    std::ofstream(script) << s.dump();
    const Outcome r = pindrag(dir, "edit " + walk() + " --script " + script + " -o " + out);
    EXPECT_NE(r.status, 0) << s;
    EXPECT_NE(r.err.find(field), std::string::npos) << field << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
  };
  json s = walk_script();
  s["edits"][0]["drag"]["link"] = "Tail";
  expect_refused(s, "/edits/0/drag/link: unknown link 'Tail'");
  s = walk_script();
  s["edits"][0]["drag"].erase("keys");
  expect_refused(s, "/edits/0/drag/keys: missing");
  s = walk_script();
  s["edits"][0]["drag"]["keys"][1]["time"] = 0.5;
  expect_refused(s, "/edits/0/drag/keys/1/time");
  s = walk_script();
  s["edits"][0]["end"] = 0.2;
  expect_refused(s, "/edits/0/end");
  s = walk_script();
  s["edits"][0]["pins"][0]["mode"] = "glue";
  expect_refused(s, "/edits/0/pins/0/mode: 'glue'");
  s = walk_script();
  s["edits"][0]["start"] = 100.0;
  s["edits"][0]["end"] = 101.0;
  expect_refused(s, "/edits/0/start");
  s = walk_script();
  s["edits"][0]["drag"]["keys"][0]["position"] = {0, "up", 0};
  expect_refused(s, "/edits/0/drag/keys/0/position/1: expected a number");
  s = walk_script();
  s["falloff"] = -1;
  expect_refused(s, "/falloff");
  expect_refused(json::array(), "expected an object");
  // not JSON at all: the line and column
  std::ofstream(script) << "{\"edits\": [";
  const Outcome r = pindrag(dir, "edit " + walk() + " --script " + script + " -o " + out);
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.err.find("edits.json:1:"), std::string::npos) << r.err;
}

TEST(EditScript, DragKeysInterpolateLinearlyAndHoldBeyondTheEnds) {
  cli::ScriptDrag d;
  d.keys = {{1.0, {0, 0, 0}}, {2.0, {0, 1, 0}}, {4.0, {0, 1, 2}}};
  EXPECT_EQ(d.at(0.0), core::Vector3(0, 0, 0));
  EXPECT_EQ(d.at(1.5), core::Vector3(0, 0.5, 0));
  EXPECT_EQ(d.at(3.0), core::Vector3(0, 1, 1));
  EXPECT_EQ(d.at(9.0), core::Vector3(0, 1, 2));
}

}  // namespace
