// Tests for `pindrag solve` (cli/solve_request.hpp): a request runs and reports per-frame errors,
// and a bad request, an unknown field included, is refused naming the field as a JSON pointer,
// both through run_solve_request and as the executable (exit status and stderr).
#include "cli/solve_request.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli/json_fields.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json request() {
  return {{"character", "arm7"},
          {"frames", 3},
          {"settings", {{"damping", 0.03}, {"gains", {{"drag", 40}}}}},
          {"drag", {{"link", "link7"}, {"target", {0.3, 0.4, 0.2}}}},
          {"pins", {{{"link", "link3"}, {"mode", "position"}}}}};
}

// The message of the RequestError that running `r` throws ("" when none).
std::string error_of(const json& r) {
  try {
    cli::run_solve_request(r);
  } catch (const cli::RequestError& e) {
    return e.what();
  }
  return "";
}

TEST(SolveRequest, RunsTheFramesAndReportsTheErrors) {
  const json out = cli::run_solve_request(request());
  EXPECT_EQ(out["character"], "arm7");
  ASSERT_EQ(out["frames"].size(), 3u);
  EXPECT_GE(out["frames"][2]["drag_error"].get<double>(), 0.0);
  EXPECT_GE(out["final"]["links"].size(), 7u);
}

TEST(SolveRequest, UnknownFieldsAreRefusedNamingThem) {
  json r = request();
  r["gravity"] = true;  // not a solve field: once silently ignored
  EXPECT_EQ(error_of(r).rfind("/gravity: unknown key (rule: one of character, frames,", 0), 0u)
      << error_of(r);
  r = request();
  r["settings"]["dampign"] = 0.1;
  EXPECT_EQ(error_of(r).rfind("/settings/dampign: unknown key", 0), 0u) << error_of(r);
  r = request();
  r["settings"]["gains"]["dragg"] = 1;
  EXPECT_EQ(error_of(r).rfind("/settings/gains/dragg: unknown key", 0), 0u) << error_of(r);
  r = request();
  r["drag"]["targte"] = {0, 0, 0};
  EXPECT_EQ(error_of(r).rfind("/drag/targte: unknown key", 0), 0u) << error_of(r);
  r = request();
  r["pins"][0]["colour"] = "red";
  EXPECT_EQ(error_of(r).rfind("/pins/0/colour: unknown key", 0), 0u) << error_of(r);
  r = request();
  r["start"] = {{"q", json::array()}, {"v", json::array()}};
  EXPECT_EQ(error_of(r).rfind("/start/v: unknown key", 0), 0u) << error_of(r);
}

TEST(SolveRequest, BadFieldsAreNamed) {
  json r = request();
  r["frames"] = 4294967297ull;  // would be 1 as a 32-bit int
  EXPECT_EQ(error_of(r), "/frames: 4294967297 is out of range (rule: an integer in [0, 1000000])");
  r = request();
  r["pins"][0]["mode"] = "glue";
  EXPECT_EQ(error_of(r), "/pins/0/mode: 'glue' is not one of position, orientation, pose");
  r = request();
  r["pins"][0]["link"] = "l_fot";
  EXPECT_EQ(error_of(r), "/pins/0/link: unknown link 'l_fot' in character 'arm7'");
  r = request();
  r["drag"]["rotation"] = {2, 0, 0, 0};
  EXPECT_EQ(error_of(r).rfind("/drag/rotation: quaternion norm is 2", 0), 0u) << error_of(r);
  r = request();
  r.erase("character");
  EXPECT_EQ(error_of(r), "/character: missing (a bundled name or a file)");
  EXPECT_EQ(error_of(json::array()), "/: expected an object, got array");
}

TEST(SolveCommand, ExitsNonZeroNamingTheUnknownField) {
  const fs::path dir =
      fs::temp_directory_path() / ("pindrag_solve_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string req = (dir / "req.json").string(), err = (dir / "stderr.txt").string();
  json r = request();
  r["gravity"] = true;
  std::ofstream(req) << r.dump();
  const std::string cmd =
      std::string(PINDRAG_EXE) + " solve --request " + req + " >/dev/null 2>" + err + " </dev/null";
  const int raw = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(raw) && WEXITSTATUS(raw) == 1) << raw;
  std::stringstream text;
  text << std::ifstream(err).rdbuf();
  EXPECT_NE(text.str().find("/gravity: unknown key"), std::string::npos) << text.str();
  // the same request without the field runs
  std::ofstream(req) << request().dump();
  EXPECT_EQ(std::system((std::string(PINDRAG_EXE) + " solve --request " + req +
                         " >/dev/null 2>/dev/null </dev/null")
                            .c_str()),
            0);
  fs::remove_all(dir);
}

}  // namespace
