// `pindrag fit`: a run on a small synthetic C3D written here, the BVH it writes, the report, and
// marker set files refused with the field named (cli/cmd_fit.cpp, cli/marker_set_file.hpp).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "animator/marker_trial.hpp"
#include "cli/commands.hpp"
#include "cli/json_fields.hpp"
#include "cli/marker_set_file.hpp"
#include "core/human_figure.hpp"
#include "io/bvh.hpp"
#include "tests/fixtures/fixtures.hpp"
#include "tests/ik/marker_fit_synthetic.hpp"

namespace {

namespace fs = std::filesystem;

void put16(std::string& s, std::size_t at, int v) {
  s[at] = static_cast<char>(v & 0xff);
  s[at + 1] = static_cast<char>((v >> 8) & 0xff);
}
std::string bytes16(int v) {
  std::string s(2, '\0');
  put16(s, 0, v);
  return s;
}
std::string bytes_float(float v) {
  std::string s(4, '\0');
  std::memcpy(s.data(), &v, 4);  // the test machine is little-endian like an Intel C3D
  return s;
}

// one parameter record of group 1 (POINT): name, type, dimensions, data
std::string parameter(const std::string& name,
                      int type,
                      const std::vector<int>& dims,
                      const std::string& data) {
  std::string body{static_cast<char>(type), static_cast<char>(dims.size())};
  for (int d : dims) body += static_cast<char>(d);
  body += data;
  body += '\0';  // no description
  return std::string{static_cast<char>(name.size()), 1} + name + bytes16(2 + body.size()) + body;
}

// A minimal Intel float C3D (C3D User Guide layout): header, POINT group, data in mm, lab Z up.
std::string c3d_file(const ik::MarkerSet& set, const ik::MarkerTrajectories& t) {
  const int points = set.size();
  std::string labels;
  for (const ik::Marker& m : set.markers) labels += m.name + std::string(4 - m.name.size(), ' ');
  std::string params = std::string{5, -1} + "POINT" + bytes16(3) + '\0';
  params += parameter("USED", 2, {}, bytes16(points));
  params += parameter("FRAMES", 2, {}, bytes16(t.frames));
  params += parameter("DATA_START", 2, {}, bytes16(3));
  params += parameter("SCALE", 4, {}, bytes_float(-1.0f));
  params += parameter("RATE", 4, {}, bytes_float(static_cast<float>(t.rate_hz)));
  params += parameter("UNITS", -1, {2}, "mm");
  params += parameter("LABELS", -1, {4, points}, labels);
  params += std::string(2, '\0');
  std::string file(1024, '\0');
  file[0] = 2;
  file[1] = 0x50;
  put16(file, 2, points);
  put16(file, 6, 1);
  put16(file, 8, t.frames);
  const std::string scale = bytes_float(-1.0f), rate = bytes_float(t.rate_hz);
  file.replace(12, 4, scale);
  put16(file, 16, 3);
  file.replace(20, 4, rate);
  file.replace(512, 4, std::string{1, 0x50, 1, 84});
  file.replace(516, params.size(), params);
  for (int f = 0; f < t.frames; ++f) {
    for (int j = 0; j < points; ++j) {
      const core::Vector3 p = t.frame_positions(f)[j] * 1000;  // world Y up → lab Z up
      const bool present = t.frame_present(f)[j];
      for (double v : {p.x(), -p.z(), p.y()}) file += bytes_float(present ? float(v) : 0.0f);
      file += bytes_float(present ? 0.0f : -1.0f);
    }
  }
  return file;
}

int run(const std::vector<std::string>& args) {
  CLI::App app;
  cli::add_fit_command(app);
  std::vector<const char*> argv{"pindrag"};
  for (const std::string& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return 0;
}

class FitCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("pindrag_fit_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(FitCommand, FitsASyntheticTrialToABvhAndAReport) {
  const auto model = core::build_human_figure();
  const ik::MarkerSet set =
      cli::read_marker_set_file(animator::bundled_marker_set_path(*model), *model);
  const core::Clip truth = marker_fit_test::smooth_motion(*model, 90, 60.0);
  const ik::MarkerTrajectories t = marker_fit_test::markers_of(*model, set, truth, 0.001, 0.2);
  std::ofstream(path("trial.c3d"), std::ios::binary) << c3d_file(set, t);
  ASSERT_EQ(run({"fit", path("trial.c3d"), "--character", "human48", "-o", path("out.bvh"),
                 "--report", path("report.json"), "--report-html", path("report.html"), "--static",
                 "0:90", "--scaled-character", path("scaled.json")}),
            0);
  const io::BvhImport bvh = io::load_bvh_file(path("out.bvh"));
  EXPECT_EQ(bvh.clip.size(), 90);
  const nlohmann::json report = cli::read_json_file(path("report.json"));
  EXPECT_LT(report["mean_error"].get<double>(), 0.004);
  EXPECT_EQ(report["frames"].size(), 90u);
  EXPECT_EQ(report["markers"]["LKNE"]["link"], "l_thigh");
  EXPECT_GT(report["us_per_frame"].get<double>(), 0);
  EXPECT_NEAR(report["scales"]["l_thigh"].get<double>(), 1.0, 0.02);
  // a trial this close to the figure never needs a second start
  EXPECT_EQ(report["second_starts"]["tried"], 0);
  EXPECT_EQ(report["second_starts"]["kept"], 0);
  EXPECT_TRUE(fs::exists(path("scaled.json")));
  // the page: the plot of the error over time (one line through the fitted frames) and one row
  // per marker of the set
  std::ifstream page_file(path("report.html"));
  const std::string page((std::istreambuf_iterator<char>(page_file)), {});
  EXPECT_NE(page.find("<h1>trial.c3d on human48</h1>"), std::string::npos);
  EXPECT_NE(page.find("<svg"), std::string::npos);
  EXPECT_NE(page.find("<path d=' M"), std::string::npos);
  std::size_t rows = 0;
  for (std::size_t at = page.find("<tr><td>"); at != std::string::npos;
       at = page.find("<tr><td>", at + 1)) {
    ++rows;
  }
  EXPECT_GE(rows, static_cast<std::size_t>(set.size()));
  EXPECT_NE(page.find("<td>LKNE</td><td>l_thigh</td>"), std::string::npos);
}

TEST_F(FitCommand, RefusesAMissingTrial) {
  EXPECT_NE(run({"fit", path("absent.c3d"), "-o", path("out.bvh")}), 0);
  EXPECT_FALSE(fs::exists(path("out.bvh")));
}

TEST(MarkerSetFile, ReadsOffsetsAndLeavesOutOffsetsToEstimate) {
  const auto model = core::build_human_figure();
  const ik::MarkerSet set = animator::parse_marker_set(nlohmann::json::parse(R"({"markers": {
      "LASI": {"link": "pelvis", "offset": [0.12, 0.07, 0.05]},
      "LKNE": {"link": "l_thigh", "weight": 2}}})"),
                                                       *model);
  ASSERT_EQ(set.size(), 2);
  const ik::Marker& asi = set.markers[set.find("LASI")];
  EXPECT_EQ(asi.link, model->link_index("pelvis"));
  EXPECT_TRUE(asi.offset.isApprox(core::Vector3(0.12, 0.07, 0.05)));
  const ik::Marker& kne = set.markers[set.find("LKNE")];
  EXPECT_FALSE(kne.offset_given);
  EXPECT_EQ(kne.weight, 2);
}

TEST(MarkerSetFile, BundledSetsHaveTheCmuLabels) {
  for (int dof : {48, 34}) {
    const auto model = core::build_human_figure({.dof = dof});
    const ik::MarkerSet set =
        cli::read_marker_set_file(animator::bundled_marker_set_path(*model), *model);
    EXPECT_EQ(set.size(), 41);
    for (const char* label : {"LFHD", "C7", "RBAC", "LFWT", "RMT5", "LFIN"})
      EXPECT_GE(set.find(label), 0) << label;
  }
}

std::string refusal(const std::string& text) {
  const auto model = core::build_human_figure();
  try {
    animator::parse_marker_set(nlohmann::json::parse(text), *model);
  } catch (const animator::MarkerSetError& e) {
    return e.what();
  }
  return "";
}

TEST(MarkerSetFile, RefusesBadFieldsNamingThem) {
  EXPECT_NE(refusal(R"({"markers": {"LASI": {"link": "pelvs"}}})").find("/markers/LASI/link"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"markers": {"LASI": {"link": "pelvis", "offset": [1, 2]}}})")
                .find("/markers/LASI/offset"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"markers": {"LASI": {"offset": [0, 0, 0]}}})").find("/markers/LASI/link"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"marker": {}})").find("/markers"), std::string::npos);
  EXPECT_NE(
      refusal(R"({"markers": {"A": {"link": "pelvis", "weight": -1}}})").find("/markers/A/weight"),
      std::string::npos);
}

TEST_F(FitCommand, RefusesABadMarkerSetNamingTheFileAndField) {
  std::ofstream(path("set.json")) << R"({"markers": {"LFHD": {"link": "skull"}}})";
  std::ofstream(path("trial.c3d")) << "x";
  testing::internal::CaptureStderr();
  EXPECT_NE(run({"fit", path("trial.c3d"), "--markers", path("set.json"), "-o", path("o.bvh")}), 0);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("set.json: /markers/LFHD/link"), std::string::npos) << err;
}

}  // namespace
