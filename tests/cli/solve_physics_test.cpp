// Tests for the physics path of `pindrag solve` (cli/solve_physics.hpp): a request with effects
// runs in a simulated world and reports the figure's balance every frame; bad combinations are
// refused naming the field; a request without effects reports exactly what it did before.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli/json_fields.hpp"
#include "cli/solve_request.hpp"
#include "core/configuration.hpp"
#include "io/bundled_characters.hpp"
#include "sim/placement.hpp"
#include "sim/support_polygon.hpp"

namespace {

using core::Vector3;
using nlohmann::json;

constexpr double kGravity = 9.81;

Vector3 vector_of(const json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

std::vector<Vector3> polygon_of(const json& j) {
  std::vector<Vector3> out;
  for (const json& p : j) out.push_back(vector_of(p));
  return out;
}

// The legs and spine held at their standing values (the standing configuration the request
// starts from).
json leg_and_spine_references() {
  const auto model = io::load_character("human48").model;
  const core::Model& m = *model;
  const Eigen::VectorXd q =
      sim::standing_configuration(m, core::rest_configuration(m), sim::GroundPlane{});
  json refs = json::object();
  for (const char* name : {"lumbar", "l_hip", "l_knee", "l_ankle", "r_hip", "r_knee", "r_ankle"}) {
    const int j = m.joint_index(name);
    const int i = m.idx_q[j];
    if (m.joint_type[j] == core::JointType::kSpherical) {
      refs[name] = {q[i], q[i + 1], q[i + 2], q[i + 3]};
    } else {
      refs[name] = q[i];
    }
  }
  return refs;
}

json standing_request() {
  return {{"character", "human48"},
          {"frames", 60},
          {"dt", 1.0 / 60},
          {"effects", {"gravity", "ground_contact", "friction", "dynamic_pins"}}};
}

std::string error_of(const json& r) {
  try {
    cli::run_solve_request(r);
  } catch (const cli::RequestError& e) {
    return e.what();
  }
  return "";
}

// Every frame of a standing figure: finite centre of mass, the centre of pressure inside the
// support polygon, the weight carried by the ground once the first landing has settled, and no
// hidden force on the root.
TEST(SolvePhysics, StandingFigureKeepsItsCenterOfPressureInsideItsSupportPolygon) {
  const double weight = io::load_character("human48").model->total_mass() * kGravity;
  for (const bool references : {false, true}) {
    SCOPED_TRACE(references ? "leg and spine references" : "no tasks");
    json r = standing_request();
    if (references) r["joint_references"] = leg_and_spine_references();
    const json out = cli::run_solve_request(r);
    ASSERT_EQ(out["frames"].size(), 60u);
    for (std::size_t k = 0; k < 60; ++k) {
      SCOPED_TRACE("frame " + std::to_string(k));
      const json& f = out["frames"][k];
      const Vector3 com = vector_of(f["com"]);
      ASSERT_TRUE(com.allFinite());
      EXPECT_NEAR(com.y(), 0.995, 0.02);
      ASSERT_FALSE(f["cop"].is_null());
      const Vector3 cop = vector_of(f["cop"]);
      EXPECT_NEAR(cop.y(), 0, 1e-12) << "on the ground";
      const std::vector<Vector3> polygon = polygon_of(f["support_polygon"]);
      ASSERT_GE(polygon.size(), 3u);
      EXPECT_TRUE(sim::inside_polygon(polygon, cop, {}, 2e-3)) << f.dump();
      if (k >= 10) {
        EXPECT_NEAR(f["contact_force"].get<double>(), weight, 0.05 * weight);
      }
      EXPECT_LT(f["base_residual"].get<double>(), 1e-9);
      EXPECT_TRUE(vector_of(f["pelvis"]).allFinite());
      EXPECT_FALSE(f["fallen"].get<bool>()) << "it stands";
      EXPECT_GE(f["microseconds"].get<double>(), 0.0);
    }
    EXPECT_EQ(out["final"]["q"].size(), 60u);
  }
}

// A drag moves the hand toward its target through the dynamics-backed pins (the left hand pulled
// 0.1 m down, a soft drag gain) while the figure stays on its feet.
TEST(SolvePhysics, DragActsThroughDynamicPins) {
  json r = standing_request();
  r["frames"] = 1;
  Vector3 hand = Vector3::Zero();
  const json standing = cli::run_solve_request(r);
  for (const json& l : standing["final"]["links"]) {
    if (l["name"] == "l_hand") hand = vector_of(l["p"]);
  }
  r["frames"] = 60;
  r["drag"] = {{"link", "l_hand"}, {"target", {hand.x(), hand.y() - 0.1, hand.z()}}, {"gain", 5}};
  const json out = cli::run_solve_request(r);
  const json& frames = out["frames"];
  EXPECT_LT(frames[59]["drag_error"].get<double>(), 0.2 * frames[0]["drag_error"].get<double>());
  for (const json& f : frames) {
    EXPECT_LT(f["base_residual"].get<double>(), 1e-9);
    ASSERT_FALSE(f["cop"].is_null());
    EXPECT_TRUE(
        sim::inside_polygon(polygon_of(f["support_polygon"]), vector_of(f["cop"]), {}, 2e-3));
  }
}

TEST(SolvePhysics, FigureInTheAirHasNoCenterOfPressure) {
  json r = standing_request();
  r["effects"] = {"gravity"};
  r["frames"] = 3;
  r["start"] = {{"q", core::rest_configuration(*io::load_character("human48").model)}};
  json& q = r["start"]["q"];
  q[1] = q[1].get<double>() + 1.0;  // a metre up
  const json out = cli::run_solve_request(r);
  for (const json& f : out["frames"]) {
    EXPECT_TRUE(f["cop"].is_null());
    EXPECT_TRUE(f["support_polygon"].empty());
    EXPECT_EQ(f["contact_force"], 0.0);
    EXPECT_EQ(f["base_residual"], 0.0);
  }
  // falling
  EXPECT_LT(out["frames"][2]["com"][1].get<double>(), out["frames"][0]["com"][1].get<double>());
}

TEST(SolvePhysics, BadEffectsAreRefusedNamingTheField) {
  json r = standing_request();
  r["effects"] = {"gravity", "wind"};
  EXPECT_EQ(error_of(r).rfind("/effects/1: 'wind' is not an effect (rule: one of gravity,", 0), 0u)
      << error_of(r);
  r = standing_request();
  r["character"] = "arm7";
  r["effects"] = {"gravity", "dynamic_pins"};
  EXPECT_EQ(error_of(r),
            "/effects: ground_contact and dynamic_pins need a free root joint; character 'arm7' "
            "has a fixed root");
  r["effects"] = {"gravity", "ground_contact"};
  EXPECT_EQ(error_of(r).rfind("/effects: ground_contact and dynamic_pins need a free root", 0), 0u)
      << error_of(r);
  r["effects"] = {"gravity"};  // an arm falling under gravity alone is fine
  EXPECT_EQ(error_of(r), "");
}

TEST(SolvePhysics, FieldsThatWouldChangeNothingAreRefused) {
  json r = standing_request();
  r["effects"] = {"gravity", "ground_contact"};
  r["pins"] = {{{"link", "l_foot"}}};
  EXPECT_EQ(error_of(r),
            "/pins: acts on a simulated body only with 'dynamic_pins' among the effects");
  r = standing_request();
  r["settings"] = {{"damping", 0.1}};
  EXPECT_EQ(error_of(r), "/settings: applies to the kinematic solver only (without effects)");
  r = standing_request();
  r.erase("effects");
  r["physics_dt"] = 0.002;
  EXPECT_EQ(error_of(r), "/physics_dt: applies only with effects");
  r = standing_request();
  r["physics_dt"] = 0;
  EXPECT_EQ(error_of(r).rfind("/physics_dt: 0 is out of range", 0), 0u) << error_of(r);
}

// Without effects (absent or empty) the request takes the kinematic path and prints exactly the
// fields it always did.
TEST(SolvePhysics, WithoutEffectsTheFramesKeepTheirFields) {
  const std::set<std::string> kinematic = {
      "drag_error",      "pin_position_error", "pin_orientation_error", "joint_speed",
      "limit_violation", "top_rank",           "microseconds",          "pin_corrections"};
  for (const json& effects : {json(), json::array()}) {
    json r = standing_request();
    r["frames"] = 2;
    r.erase("effects");
    if (!effects.is_null()) r["effects"] = effects;
    const json out = cli::run_solve_request(r);
    for (const json& f : out["frames"]) {
      std::set<std::string> keys;
      for (const auto& [key, value] : f.items()) keys.insert(key);
      EXPECT_EQ(keys, kinematic);
    }
    EXPECT_EQ(out.size(), 3u);  // character, frames, final
  }
}

TEST(SupportPolygon, HullIsCounterClockwiseSeenFromAbove) {
  const std::vector<Vector3> points = {{0, -0.01, 0},  {1, 0, 0},   {1, 0.02, -1}, {0, 0, -1},
                                       {0.5, 0, -0.5}, {0.5, 0, 0}, {1, 0, 0}};
  const std::vector<Vector3> hull = sim::support_polygon(points, {});
  ASSERT_EQ(hull.size(), 4u);  // interior, edge and repeated points dropped
  double twice_area = 0;       // about +y: (z x − x z) summed
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Vector3& a = hull[i];
    const Vector3& b = hull[(i + 1) % hull.size()];
    EXPECT_EQ(a.y(), 0) << "projected onto the ground";
    twice_area += a.z() * b.x() - a.x() * b.z();
  }
  EXPECT_NEAR(twice_area, 2.0, 1e-12);  // positive: counter-clockwise seen from +y
  EXPECT_TRUE(sim::inside_polygon(hull, {0.5, 0.3, -0.5}, {}, 0));
  EXPECT_TRUE(sim::inside_polygon(hull, {1.001, 0, -0.5}, {}, 2e-3));
  EXPECT_FALSE(sim::inside_polygon(hull, {1.01, 0, -0.5}, {}, 2e-3));
  EXPECT_FALSE(sim::inside_polygon({}, {0, 0, 0}, {}, 1));
}

TEST(SupportPolygon, CollinearPointsGiveASegmentAndATiltedPlaneWorks) {
  const std::vector<Vector3> line = sim::support_polygon({{0, 0, 0}, {1, 0, 0}, {0.5, 0, 0}}, {});
  ASSERT_EQ(line.size(), 2u);
  EXPECT_TRUE(sim::inside_polygon(line, {0.5, 0, 0.001}, {}, 2e-3));
  EXPECT_FALSE(sim::inside_polygon(line, {1.5, 0, 0}, {}, 2e-3));
  sim::GroundPlane tilted;
  tilted.normal = Vector3(1, 1, 0).normalized();
  tilted.point = Vector3(0, 1, 0);
  const std::vector<Vector3> square = {
      {0, 1, 0}, {0, 1, 1}, {-1, 2, 0}, {-1, 2, 1}, {-0.5, 1.5, 0.5}};
  const std::vector<Vector3> hull = sim::support_polygon(square, tilted);
  ASSERT_EQ(hull.size(), 4u);
  for (const Vector3& p : hull) EXPECT_NEAR((p - tilted.point).dot(tilted.normal), 0, 1e-12);
  EXPECT_TRUE(sim::inside_polygon(hull, Vector3(-0.5, 1.5, 0.5) + tilted.normal, tilted, 0));
}

}  // namespace
