// `pindrag simulate`: the scene file, the recorded output and the refusals (cli/simulate_scene).
#include <gtest/gtest.h>

#include "cli/json_fields.hpp"
#include "cli/simulate_scene.hpp"

namespace {

using nlohmann::json;

TEST(SimulateCommand, RecordsTheBooksSlidingBox) {
  cli::SimulationRun run = cli::read_simulation_scene(json::parse(R"({
    "bodies": [{"name": "crate", "shape": "box", "size": [0.2, 0.2, 0.2], "mass": 1,
                "position": [0, 0.0999, 0], "velocity": [1, 0, 0]}],
    "effects": ["gravity", "ground_contact", "friction"],
    "contact": {"mu_static": 0.35, "mu_dynamic": 0.25, "kfp": 1000, "kfd": 700},
    "duration": 0.6, "record_every": 100})"));
  const json out = cli::run_simulation(run);
  ASSERT_EQ(out["frames"].size(), 7u);  // t = 0, 0.1, ..., 0.6
  const json& last = out["frames"].back();
  EXPECT_NEAR(last["t"].get<double>(), 0.6, 1e-9);
  EXPECT_NEAR(last["bodies"][0]["p"][0].get<double>(), 0.204, 0.006);  // Coulomb's stop
  EXPECT_NEAR(last["bodies"][0]["v"][0].get<double>(), 0.0, 1e-3);
  ASSERT_EQ(last["contacts"].size(), 1u);
  EXPECT_NEAR(last["contacts"][0]["force"][1].get<double>(), 9.81, 0.01);  // its weight
  EXPECT_EQ(out["stages"]["integration"].get<int>(), 600);
  EXPECT_EQ(out["stages"]["limit_projection"].get<int>(), 0);
  EXPECT_GT(out["us_per_step"].get<double>(), 0);
}

TEST(SimulateCommand, ACharacterStartsStandingOnTheGround) {
  cli::SimulationRun run = cli::read_simulation_scene(
      json::parse(R"({"character": "human48", "effects": [], "duration": 0.01})"));
  const json out = cli::run_simulation(run);
  EXPECT_TRUE(out["frames"][0]["contacts"].empty());  // no effect: no contact search
  EXPECT_EQ(out["stages"]["kinematics"].get<int>(), 0);
  EXPECT_EQ(out["stages"]["mass_matrix"].get<int>(), 0);
}

TEST(SimulateCommand, BadScenesNameTheField) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"effects": ["gravity", "wind"]})", "/effects/1"},
      {R"({"dt": -0.001})", "/dt"},
      {R"({"bodies": [{"name": "b", "shape": "box", "size": [1, 1, 1], "mass": -2}]})",
       "/bodies/0/mass"},
      {R"({"bodies": [{"name": "b", "shape": "cone", "mass": 1}]})", "/bodies/0/shape"},
      {R"({"ground": {"normal": [0, 2, 0]}})", "/ground/normal"},
      {R"({"contact": {"mu_static": 0.2, "mu_dynamic": 0.3}})", "/contact/mu_dynamic"},
      {R"({"integrator": "verlet"})", "/integrator"},
      {R"({"effect": ["gravity"]})", "/effect"},
      {R"({"character": "no_such_character"})", "/character"},
  };
  for (const auto& [scene, field] : cases) {
    try {
      cli::read_simulation_scene(json::parse(scene));
      ADD_FAILURE() << "accepted " << scene;
    } catch (const cli::RequestError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(field, 0), 0u) << e.what();
    }
  }
}

}  // namespace
