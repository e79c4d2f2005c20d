// Tests for reading session files (animator/session_file.hpp): bad files are refused with the
// field named as a JSON pointer (or the line and column of a syntax error), integers are range
// checked instead of wrapped, the solver settings refuse unknown keys, and a character's BVH
// source is kept.
#include "animator/session_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "core/human_figure.hpp"
#include "io/bvh.hpp"
#include "tests/animator/animator_fixtures.hpp"

namespace {

using namespace animator;
using animator_test::human;
using animator_test::session_file_error;
using nlohmann::json;

// A saved session with a pin, a key and an edit layer.
json saved() {
  Session s(human(), "human48");
  s.pin(s.model().link_index("l_foot"), ik::TaskMode::kPose);
  s.key_insert(0.0);
  return session_to_json(s);
}

TEST(SessionFile, BadFieldsAreNamedAsPointers) {
  json j = saved();
  EXPECT_EQ(session_file_error(j), "");
  j["pins"][0]["mode"] = "glue";
  EXPECT_EQ(session_file_error(j), "/pins/0/mode: 'glue' is not position, orientation or pose");
  j = saved();
  j["pins"][0]["rotation"] = {2, 0, 0, 0};
  EXPECT_EQ(session_file_error(j).rfind("/pins/0/rotation: quaternion [w, x, y, z] has norm 2", 0),
            0u);
  j = saved();
  j["keys"][0]["q"][3] = "x";
  EXPECT_EQ(session_file_error(j), "/keys/0/q/3: expected a number, got a string");
  j = saved();
  j["playback"].erase("speed");
  EXPECT_EQ(session_file_error(j), "/playback/speed: missing (rule: required)");
  j = saved();
  j["scene"]["gravity"] = "yes";
  EXPECT_EQ(session_file_error(j), "/scene/gravity: expected true or false, got a string");
  j = saved();
  j["format"] = 3;
  EXPECT_EQ(session_file_error(j), "test.json: not a pindrag session file");
}

TEST(SessionFile, IntegersAreRangeCheckedNotWrapped) {
  json j = saved();
  // 4294967297 iterations would be 1 as a 32-bit int
  j["settings"]["iterations"] = 4294967297ull;
  EXPECT_EQ(session_file_error(j).rfind("/settings/iterations: 4294967297 is out of range", 0), 0u)
      << session_file_error(j);
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

// A two-joint BVH in centimetres with different orders per joint.
constexpr const char* kMixedOrders =
    "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\n"
    "CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\n"
    "JOINT Chest\n{\nOFFSET 0 85.5 0\nCHANNELS 3 Zrotation Yrotation Xrotation\n"
    "End Site\n{\nOFFSET 0 80.25 0\n}\n}\n}\nMOTION\nFrames: 2\nFrame Time: 0.01\n"
    "1 90 2 10 20 30 40 -50 60\n2 91 3 11 21 31 41 -51 61\n";

TEST(SessionFile, TheBvhSourceOfTheCharacterIsSavedAndRead) {
  io::BvhImport imp = io::load_bvh_string(kMixedOrders, "mixed.bvh");
  ASSERT_DOUBLE_EQ(imp.layout.scale, 0.01);
  Session s(imp.model, "mixed");
  s.set_clip(imp.clip, "import clip");
  EXPECT_FALSE(session_to_json(s).contains("bvh_source"));  // none yet
  s.set_bvh_source(std::make_shared<const io::BvhLayout>(imp.layout));
  const json j = session_to_json(s);
  EXPECT_EQ(j.at("bvh_source").at("joints").at(1),
            json({{"name", "Chest"}, {"channels", {"Zrotation", "Yrotation", "Xrotation"}}}));
  EXPECT_FALSE(session_to_json(s, /*include_character=*/false).contains("bvh_source"));

  const auto loaded = session_from_json(j, "test.json");
  ASSERT_TRUE(loaded->bvh_source());
  const io::BvhLayout& layout = *loaded->bvh_source();
  EXPECT_EQ(layout.scale, imp.layout.scale);
  ASSERT_EQ(layout.joints.size(), imp.layout.joints.size());
  for (std::size_t k = 0; k < layout.joints.size(); ++k) {
    EXPECT_EQ(layout.joints[k].name, imp.layout.joints[k].name);
    EXPECT_EQ(layout.joints[k].channels, imp.layout.joints[k].channels);
  }
  // the reloaded session exports the same file as the one it was saved from
  io::BvhExportOptions before, after;
  before.layout = &imp.layout;
  after.layout = loaded->bvh_source().get();
  EXPECT_EQ(io::write_bvh(loaded->model(), *loaded->clip(), after),
            io::write_bvh(*imp.model, imp.clip, before));
}

TEST(SessionFile, BadBvhSourcesAreNamed) {
  Session s(io::load_bvh_string(kMixedOrders, "mixed.bvh").model, "mixed");
  s.set_bvh_source(
      std::make_shared<const io::BvhLayout>(io::load_bvh_string(kMixedOrders, "m.bvh").layout));
  const json good = session_to_json(s);
  json j = good;
  j["bvh_source"]["joints"][1]["channels"][0] = "Wrotation";
  EXPECT_EQ(session_file_error(j),
            "/bvh_source/joints/1/channels/0: 'Wrotation' is not a BVH channel");
  j = good;
  j["bvh_source"]["joints"][1]["channels"][1] = "Zrotation";
  EXPECT_EQ(session_file_error(j), "/bvh_source/joints/1/channels/1: 'Zrotation' is listed twice");
  j = good;
  j["bvh_source"]["joints"][1]["name"] = "Hips";
  EXPECT_EQ(session_file_error(j), "/bvh_source/joints/1/name: names a joint twice");
  j = good;
  j["bvh_source"]["scale"] = 0;
  EXPECT_EQ(session_file_error(j), "/bvh_source/scale: must be positive (metres per file unit)");
  j = good;
  j.erase("bvh_source");
  EXPECT_EQ(session_file_error(j), "");
}

}  // namespace
