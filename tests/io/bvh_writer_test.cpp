// Tests for io/bvh_writer.hpp: the source convention of an imported BVH (its unit and each
// joint's rotation order) is what an export keeps by default, the units and order options
// override it, their values are parsed with messages naming the option, and re-importing any
// export gives the original world poses. Whole-file round trips of every shared file are in
// bvh_test.cpp.
#include "io/bvh_writer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

using io::BvhChannel;
using io::BvhDocument;
using io::BvhExportOptions;
using io::BvhImport;
using io::BvhImportOptions;

// A small skeleton in centimetres (about 170 tall) with ZXY channels, as CMU-style files are:
// a 6-channel ROOT at OFFSET 0 0 0, one joint with only two rotation channels, End Sites, and
// motion values with at most 6 decimals (so that %.6f writes them back exactly), the middle angle
// inside (-90°, 90°) and the others inside (-180°, 180°) with no jumps (so that the writer's
// unwrapped decomposition is the file's own).
constexpr const char* kCentimetreZxy = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10.5 -1.25
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT Head
    {
      OFFSET 0.5 62.75 2
      CHANNELS 3 Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 0 18.125 0
      }
    }
  }
  JOINT LeftUpLeg
  {
    OFFSET 9.5 -4 0.25
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -44.5 0.75
      CHANNELS 2 Zrotation Xrotation
      JOINT LeftFoot
      {
        OFFSET 0 -41.25 -1.5
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -3.5 12.25
        }
      }
    }
  }
}
MOTION
Frames: 4
Frame Time: 0.008333
1.5 92.25 -3.125 5 -10 20 12.5 30.25 -45.5 -170.125 60 175.5 30 -20 -5 0 65 10 -15 2.5
2.75 93.5 -1.25 7.5 -12.75 24.125 15 28 -40 -168.5 62.5 178.25 32.5 -22.25 -7.5 0 70.125 12 -14 3
4 94.125 0.5 10 -15.5 27.75 17.5 26.5 -35.25 -166.75 65 179.5 35 -24 -10.25 0 75.5 14.5 -13 3.5
5.25 95 2.25 12.25 -18 31.5 20 25 -30 -165 67.25 179.875 37.5 -26.5 -12.5 0 80 16 -12 4
)";

// the inline file, parsed and imported (automatic scale)
struct Source {
  BvhDocument doc;
  BvhImport imp;
};
Source source() {
  Source s;
  s.doc = io::parse_bvh(kCentimetreZxy, "cm_zxy.bvh");
  s.imp = io::import_bvh(s.doc, "cm_zxy.bvh");
  return s;
}

std::string rotation_order(const io::BvhNode& node) {
  std::string order;
  for (BvhChannel c : node.channels) {
    if (io::is_rotation(c)) order += static_cast<char>('X' + io::channel_axis(c));
  }
  return order;
}

// |a - b| within `relative` of |a| (absolutely for |a| < 1)
void expect_close(double b, double a, double relative, const std::string& what) {
  EXPECT_NEAR(b, a, relative * std::max(1.0, std::abs(a))) << what;
}

// every node's OFFSET of `b` equals `a`'s times `factor` (same hierarchy)
void expect_offsets(const BvhDocument& b, const BvhDocument& a, double factor) {
  ASSERT_EQ(b.nodes.size(), a.nodes.size());
  for (std::size_t k = 0; k < a.nodes.size(); ++k) {
    for (int c = 0; c < 3; ++c) {
      expect_close(b.nodes[k].offset[c], a.nodes[k].offset[c] * factor, 1e-6,
                   a.nodes[k].name + " OFFSET " + std::to_string(c));
    }
  }
}

// Re-imports `doc` (an export of `s` written at `scale` metres per unit) and expects every link
// of the original model at the same world position on every frame, within `tolerance` metres.
void expect_same_world_poses(const BvhImport& original,
                             const BvhDocument& doc,
                             double scale,
                             double tolerance) {
  BvhImportOptions o;
  o.scale = scale;
  const BvhImport back = io::import_bvh(doc, "exported.bvh", o);
  const core::Model& ma = *original.model;
  const core::Model& mb = *back.model;
  ASSERT_EQ(back.clip.size(), original.clip.size());
  core::Data da(ma), db(mb);
  double worst = 0;
  for (int f = 0; f < original.clip.size(); ++f) {
    core::forward_kinematics(ma, da, original.clip.frames[f]);
    core::forward_kinematics(mb, db, back.clip.frames[f]);
    for (int i = 1; i < ma.njoints; ++i) {
      const int j = mb.link_index(ma.link_name[i]);
      ASSERT_GE(j, 1) << ma.link_name[i];
      worst = std::max(worst, (da.X_W[i].p - db.X_W[j].p).norm());
    }
  }
  EXPECT_LT(worst, tolerance);
}

TEST(BvhExportOptionValues, ParseWithMessagesNamingTheOption) {
  EXPECT_EQ(io::parse_bvh_units("m", "--units"), 1.0);
  EXPECT_EQ(io::parse_bvh_units("CM", "--units"), 0.01);
  EXPECT_EQ(io::parse_bvh_units("source", "--units"), std::nullopt);
  EXPECT_EQ(io::parse_bvh_order("zxy", "order"), "ZXY");
  EXPECT_EQ(io::parse_bvh_order("Source", "order"), std::nullopt);
  for (const char* order : {"XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"}) {
    EXPECT_EQ(io::parse_bvh_order(order, "order"), order);
  }
  try {
    io::parse_bvh_units("inch", "--units");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--units: 'inch' (rule: one of m, cm, source)");
  }
  try {
    io::parse_bvh_order("XXY", "order");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "order: 'XXY' (rule: one of XYZ, XZY, YXZ, YZX, ZXY, ZYX, source)");
  }
}

TEST(BvhExportConvention, TheImportKeepsTheSourceUnitAndOrders) {
  const Source s = source();
  EXPECT_EQ(s.imp.unit, "centimetres");
  EXPECT_DOUBLE_EQ(s.imp.layout.scale, 0.01);
  ASSERT_EQ(s.imp.layout.joints.size(), 6u);
  EXPECT_EQ(s.imp.layout.joints[4].name, "LeftLeg");
  EXPECT_EQ(s.imp.layout.joints[4].channels,
            (std::vector<BvhChannel>{BvhChannel::kZrotation, BvhChannel::kXrotation}));
}

TEST(BvhExportConvention, ByDefaultAnExportIsTheSourceFileAgain) {
  const Source s = source();
  BvhExportOptions o;
  o.layout = &s.imp.layout;
  const std::string text = io::write_bvh(*s.imp.model, s.imp.clip, o);
  // "source" spelled out is the default
  BvhExportOptions spelled = o;
  spelled.scale = io::parse_bvh_units("source", "units");
  spelled.rotation_order = io::parse_bvh_order("source", "order");
  EXPECT_EQ(io::write_bvh(*s.imp.model, s.imp.clip, spelled), text);

  const BvhDocument out = io::parse_bvh(text, "exported.bvh");
  // same nodes, channel lists (LeftLeg's missing Y appended last), OFFSETs in centimetres
  ASSERT_EQ(out.nodes.size(), s.doc.nodes.size());
  for (std::size_t k = 0; k < out.nodes.size(); ++k) {
    EXPECT_EQ(out.nodes[k].name, s.doc.nodes[k].name);
    EXPECT_EQ(out.nodes[k].kind, s.doc.nodes[k].kind);
    const std::string expected = s.doc.nodes[k].name == "LeftLeg" ? "ZXY"
                                 : out.nodes[k].is_end_site()     ? ""
                                                                  : rotation_order(s.doc.nodes[k]);
    EXPECT_EQ(rotation_order(out.nodes[k]), expected) << out.nodes[k].name;
    if (s.doc.nodes[k].name != "LeftLeg") {
      EXPECT_EQ(out.nodes[k].channels, s.doc.nodes[k].channels);
    }
  }
  expect_offsets(out, s.doc, 1.0);
  // motion values: positions in centimetres, angles in degrees, as in the source
  ASSERT_EQ(out.frames, s.doc.frames);
  for (int f = 0; f < out.frames; ++f) {
    for (std::size_t k = 0; k < out.nodes.size(); ++k) {
      const io::BvhNode& a = s.doc.nodes[k];
      const io::BvhNode& b = out.nodes[k];
      for (std::size_t c = 0; c < a.channels.size(); ++c) {
        const double va = s.doc.frame(f)[a.first_value + c];
        const double vb = out.frame(f)[b.first_value + c];
        if (io::is_rotation(a.channels[c])) {
          EXPECT_NEAR(vb, va, 1e-6) << a.name << " frame " << f << " channel " << c;
        } else {
          expect_close(vb, va, 1e-6, a.name + " position");
        }
      }
    }
  }
  // the re-imported text is the same motion
  expect_same_world_poses(s.imp, out, 0.01, 1e-9);
}

TEST(BvhExportConvention, ExplicitUnitsAndOrderOverrideTheSource) {
  const Source s = source();
  BvhExportOptions o;
  o.layout = &s.imp.layout;
  o.scale = io::parse_bvh_units("cm", "units");
  o.rotation_order = io::parse_bvh_order("XYZ", "order");
  const BvhDocument cm_xyz = io::parse_bvh(io::write_bvh(*s.imp.model, s.imp.clip, o), "a.bvh");
  for (const io::BvhNode& node : cm_xyz.nodes) {
    if (!node.is_end_site()) {
      EXPECT_EQ(rotation_order(node), "XYZ") << node.name;
    }
  }
  expect_offsets(cm_xyz, s.doc, 1.0);
  for (int f = 0; f < cm_xyz.frames; ++f) {
    for (int c = 0; c < 3; ++c) expect_close(cm_xyz.frame(f)[c], s.doc.frame(f)[c], 1e-6, "root");
  }

  o.scale = io::parse_bvh_units("m", "units");
  o.rotation_order = io::parse_bvh_order("ZYX", "order");
  const BvhDocument m_zyx = io::make_bvh_document(*s.imp.model, s.imp.clip, o);
  for (const io::BvhNode& node : m_zyx.nodes) {
    if (!node.is_end_site()) {
      EXPECT_EQ(rotation_order(node), "ZYX") << node.name;
    }
  }
  expect_offsets(m_zyx, s.doc, 0.01);
  for (int f = 0; f < m_zyx.frames; ++f) {
    for (int c = 0; c < 3; ++c) {
      expect_close(m_zyx.frame(f)[c], 0.01 * s.doc.frame(f)[c], 1e-9, "root");
    }
  }
}

// Every combination of unit and order: the written document re-imports to the original world
// poses within 1e-9 m. The text rounds angles to 1e-6° (about 2e-8 rad), so a new decomposition
// read back from the text agrees within 1e-7 m (about 1e-8 m here); the source orders, exactly.
TEST(BvhExportConvention, ReimportingAnyExportGivesTheSameWorldPoses) {
  const Source s = source();
  for (const char* units : {"source", "m", "cm"}) {
    for (const char* order : {"source", "XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"}) {
      SCOPED_TRACE(std::string(units) + " " + order);
      BvhExportOptions o;
      o.layout = &s.imp.layout;
      o.scale = io::parse_bvh_units(units, "units");
      o.rotation_order = io::parse_bvh_order(order, "order");
      const double scale = o.scale.value_or(s.imp.layout.scale);
      const BvhDocument doc = io::make_bvh_document(*s.imp.model, s.imp.clip, o);
      expect_same_world_poses(s.imp, doc, scale, 1e-9);
      const BvhDocument text = io::parse_bvh(io::format_bvh(doc), "exported.bvh");
      expect_same_world_poses(s.imp, text, scale, 1e-7);
    }
  }
}

// A real CMU file with mixed per-joint orders (19 joints ZYX, 12 ZXY) in CMU units.
TEST(BvhExportConvention, ASharedCmuFileKeepsItsOrdersAndOffsets) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string path = fixtures::data_dir() + "/bvh/cmu_131_01_mj_walk_3dsmax.bvh";
  std::ifstream in(path, std::ios::binary);
  ASSERT_TRUE(in) << path;
  std::stringstream text;
  text << in.rdbuf();
  const BvhDocument a = io::parse_bvh(text.str(), path);
  const BvhImport imp = io::import_bvh(a, path);
  EXPECT_DOUBLE_EQ(imp.layout.scale, io::kCmuUnit);
  BvhExportOptions o;
  o.layout = &imp.layout;
  const BvhDocument b = io::parse_bvh(io::write_bvh(*imp.model, imp.clip, o), path + " (out)");
  ASSERT_EQ(b.nodes.size(), a.nodes.size());
  int zxy = 0, zyx = 0;
  for (std::size_t k = 0; k < a.nodes.size(); ++k) {
    EXPECT_EQ(b.nodes[k].name, a.nodes[k].name);
    EXPECT_EQ(b.nodes[k].channels, a.nodes[k].channels) << a.nodes[k].name;
    zxy += rotation_order(b.nodes[k]) == "ZXY";
    zyx += rotation_order(b.nodes[k]) == "ZYX";
  }
  EXPECT_EQ(zxy, 12);
  EXPECT_EQ(zyx, 19);
  expect_offsets(b, a, 1.0);
  EXPECT_EQ(b.frames, a.frames);
  expect_same_world_poses(imp, io::make_bvh_document(*imp.model, imp.clip, o), io::kCmuUnit, 1e-9);
}

}  // namespace
