// `pindrag retarget` run as the executable: output clip, report, and field-named refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/fixtures/fixtures.hpp"
#include "tests/fixtures/run_pindrag.hpp"

namespace {

using fixtures::Outcome;
using fixtures::slurp;

struct Dir {
  std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("pindrag_retarget_" + std::to_string(::getpid()));
  Dir() { std::filesystem::create_directories(path); }
  ~Dir() { std::filesystem::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

Outcome pindrag(const Dir& dir, const std::string& args) {
  return fixtures::run_pindrag(PINDRAG_EXE, dir.path.string(), args);
}

std::string mixamo() { return fixtures::data_dir() + "/bvh/mixamo_naming_freebvh.bvh"; }

TEST(RetargetCommand, WritesClipAndReport) {
  PINDRAG_REQUIRE_DATA_DIR();
  Dir dir;
  const Outcome r = pindrag(dir, "retarget " + mixamo() + " --to human48 -o " +
                                     dir.file("out.bvh") + " --report " + dir.file("report.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(slurp(dir.file("out.bvh")).find("HIERARCHY"), std::string::npos);
  const auto report = nlohmann::json::parse(slurp(dir.file("report.json")));
  EXPECT_EQ(report["frames"], 69);
  EXPECT_EQ(report["source_convention"], "mixamo");
  EXPECT_EQ(report["mapping"]["mixamorig:LeftArm"], "l_uarm");
  EXPECT_TRUE(report["unmapped_source_joints"].is_array());
  EXPECT_GT(report["contacts"].size(), 0u);
  EXPECT_TRUE(report.contains("max_foot_slide_m"));
  EXPECT_EQ(report["range_violation"]["frames_out_of_range"], 0);
}

TEST(RetargetCommand, MappingOverridesAndRefusals) {
  PINDRAG_REQUIRE_DATA_DIR();
  Dir dir;
  const std::string map = dir.file("map.json");
  std::ofstream(map) << R"({"mixamorig:LeftHand": null})";
  Outcome r = pindrag(dir, "retarget " + mixamo() + " --to human34 -o " + dir.file("out.glb") +
                               " --mapping " + map + " --report " + dir.file("report.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto report = nlohmann::json::parse(slurp(dir.file("report.json")));
  EXPECT_FALSE(report["mapping"].contains("mixamorig:LeftHand"));

  std::ofstream(map) << R"({"NoSuchJoint": "l_hand"})";
  r = pindrag(
      dir, "retarget " + mixamo() + " --to human48 -o " + dir.file("o.bvh") + " --mapping " + map);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("NoSuchJoint"), std::string::npos) << r.err;
  std::ofstream(map) << R"({"mixamorig:LeftHand": "no_link"})";
  r = pindrag(
      dir, "retarget " + mixamo() + " --to human48 -o " + dir.file("o.bvh") + " --mapping " + map);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no_link"), std::string::npos) << r.err;
  std::ofstream(map) << R"({"mixamorig:LeftHand": 3})";
  r = pindrag(
      dir, "retarget " + mixamo() + " --to human48 -o " + dir.file("o.bvh") + " --mapping " + map);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("/mixamorig:LeftHand"), std::string::npos) << r.err;
  // the legs unmapped: refused, naming the rule
  std::ofstream(map) << R"({"mixamorig:LeftUpLeg": null})";
  r = pindrag(
      dir, "retarget " + mixamo() + " --to human48 -o " + dir.file("o.bvh") + " --mapping " + map);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("l_thigh"), std::string::npos) << r.err;
  r = pindrag(dir, "retarget " + mixamo() + " --to nobody -o " + dir.file("o.bvh"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("nobody"), std::string::npos) << r.err;
}

}  // namespace
