// Tests for reading session files (animator/session_file.hpp): bad files are refused with the
// field named as a JSON pointer (or the line and column of a syntax error), integers are range
// checked instead of wrapped, and the solver settings refuse unknown keys.
#include "animator/session_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/human_figure.hpp"

namespace {

using namespace animator;
using nlohmann::json;

std::shared_ptr<const core::Model> human() {
  static const auto m = core::build_human_figure({});
  return m;
}

// A saved session with a pin, a key and an edit layer.
json saved() {
  Session s(human(), "human48");
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  s.key_insert(0.0);
  return session_to_json(s);
}

// The message of the SessionError that reading `j` throws ("" when none).
std::string error_of(const json& j) {
  try {
    session_from_json(j, "test.json");
  } catch (const SessionError& e) {
    return e.what();
  }
  return "";
}

TEST(SessionFile, BadFieldsAreNamedAsPointers) {
  json j = saved();
  EXPECT_EQ(error_of(j), "");
  j["pins"][0]["mode"] = "glue";
  EXPECT_EQ(error_of(j), "/pins/0/mode: 'glue' is not position, orientation or pose");
  j = saved();
  j["pins"][0]["rotation"] = {2, 0, 0, 0};
  EXPECT_EQ(error_of(j).rfind("/pins/0/rotation: quaternion [w, x, y, z] has norm 2", 0), 0u);
  j = saved();
  j["keys"][0]["q"][3] = "x";
  EXPECT_EQ(error_of(j), "/keys/0/q/3: expected a number, got a string");
  j = saved();
  j["playback"].erase("speed");
  EXPECT_EQ(error_of(j), "/playback/speed: missing (rule: required)");
  j = saved();
  j["scene"]["gravity"] = "yes";
  EXPECT_EQ(error_of(j), "/scene/gravity: expected true or false, got a string");
  j = saved();
  j["format"] = 3;
  EXPECT_EQ(error_of(j), "test.json: not a pindrag session file");
}

TEST(SessionFile, IntegersAreRangeCheckedNotWrapped) {
  json j = saved();
  // 4294967297 iterations would be 1 as a 32-bit int
  j["settings"]["iterations"] = 4294967297ull;
  EXPECT_EQ(error_of(j).rfind("/settings/iterations: 4294967297 is out of range", 0), 0u)
      << error_of(j);
  ik::SolverSettings s;
  EXPECT_THROW(settings_from_json({{"iterations", 4294967297ull}}, s), SessionError);
  EXPECT_EQ(s.iterations, ik::SolverSettings{}.iterations);
}

TEST(SessionFile, SettingsRefuseUnknownKeysAndBadValues) {
  ik::SolverSettings s;
  try {
    settings_from_json({{"dampign", 0.1}}, s);
    ADD_FAILURE() << "no SessionError";
  } catch (const SessionError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("settings/dampign: unknown key", 0), 0u) << e.what();
  }
  try {
    settings_from_json({{"gains", {{"drag", "fast"}}}}, s);
    ADD_FAILURE() << "no SessionError";
  } catch (const SessionError& e) {
    EXPECT_EQ(std::string(e.what()), "settings/gains/drag: expected a number, got a string");
  }
  settings_from_json({{"damping", 0.05}, {"gains", {{"pin", 30}}}}, s);
  EXPECT_EQ(s.damping, 0.05);
  EXPECT_EQ(s.pin_gain, 30);
}

TEST(SessionFile, DamagedFilesNameTheLineAndColumn) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("pindrag_session_file_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << "{\n  \"format\": \"pindrag-session\",\n  \"version\": 1,,\n}";
  try {
    load_session(path.string());
    ADD_FAILURE() << "no SessionError";
  } catch (const SessionError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(path.string() + ": line 3, column 16: syntax error", 0),
              0u)
        << e.what();
  }
  std::ofstream(path) << R"({"format": "pindrag-session", "format": "x"})";
  try {
    load_session(path.string());
    ADD_FAILURE() << "no SessionError";
  } catch (const SessionError& e) {
    EXPECT_EQ(std::string(e.what()).find(path.string() + ": /format: duplicate key"), 0u)
        << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(load_session(path.string()), SessionError);
  // saving into a folder that does not exist names the path
  try {
    Session s(human(), "human48");
    save_session(s, "/nonexistent/dir/session.json");
    ADD_FAILURE() << "no SessionError";
  } catch (const SessionError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/session.json"), std::string::npos);
  }
}

}  // namespace
