// Tests for cli/dynamics_state.hpp (`pindrag dynamics`): states read by joint name, the output
// equals the core algorithms on the same state, and every bad input names its field.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cli/dynamics_state.hpp"
#include "cli/json_fields.hpp"
#include "core/aba.hpp"
#include "core/configuration.hpp"
#include "core/crba.hpp"
#include "core/human_figure.hpp"
#include "core/model_edit.hpp"
#include "core/rnea.hpp"
#include "io/bundled_characters.hpp"

namespace {

using nlohmann::json;

std::shared_ptr<const core::Model> human48() { return core::build_human_figure({}); }

// the state below for the human figure: free root, a spherical joint and a revolute joint
json human_state() {
  const double s = std::sqrt(0.5);
  return {
      {"q",
       {{"root", {0.1, 0.9, -0.2, s, 0, s, 0}}, {"l_shoulder", {s, s, 0, 0}}, {"l_elbow", 0.7}}},
      {"v",
       {{"root", {0.1, -0.2, 0.3, 0.5, 0.0, -0.4}}, {"l_shoulder", {1, 2, 3}}, {"l_elbow", -1.5}}},
      {"a", {{"root", {0, 0, 0, 0, 9.81, 0}}, {"l_elbow", 2.0}}},
      {"tau", {{"l_shoulder", {1, -1, 0.5}}, {"l_elbow", 3.0}, {"r_elbow", -2.0}}}};
}

TEST(DynamicsCommand, ReadsJointsByNameAndDefaultsTheRest) {
  const auto m = human48();
  const cli::NamedState s = cli::read_named_state(*m, human_state());
  const int root = m->joint_index("root"), shoulder = m->joint_index("l_shoulder"),
            elbow = m->joint_index("l_elbow");
  ASSERT_GT(root, 0);
  // free q: [x, y, z, w, qx, qy, qz] → position then (w, x, y, z)
  EXPECT_DOUBLE_EQ(s.q[m->idx_q[root] + 1], 0.9);
  EXPECT_NEAR(core::quaternion_at(s.q, m->idx_q[root] + 3).y(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(core::quaternion_at(s.q, m->idx_q[shoulder]).x(), std::sqrt(0.5), 1e-15);
  EXPECT_DOUBLE_EQ(s.q[m->idx_q[elbow]], 0.7);
  EXPECT_DOUBLE_EQ(s.v[m->idx_v[root] + 3], 0.5);
  EXPECT_DOUBLE_EQ(s.v[m->idx_v[shoulder] + 2], 3.0);
  EXPECT_DOUBLE_EQ(s.a[m->idx_v[root] + 4], 9.81);
  EXPECT_DOUBLE_EQ(s.tau[m->idx_v[m->joint_index("r_elbow")]], -2.0);
  // everything not named is neutral or zero
  const int knee = m->joint_index("r_knee");
  ASSERT_GT(knee, 0);
  EXPECT_EQ(s.q[m->idx_q[knee]], 0.0);
  EXPECT_EQ(core::quaternion_at(s.q, m->idx_q[m->joint_index("r_shoulder")]).w(), 1.0);
  EXPECT_NEAR(s.v.squaredNorm(), 0.55 + 14 + 2.25, 1e-12);
  EXPECT_EQ(core::check_configuration(*m, s.q), "");
  // an empty state is the neutral state at rest
  const cli::NamedState e = cli::read_named_state(*m, json::object());
  EXPECT_EQ(e.q, core::neutral_configuration(*m));
  EXPECT_EQ(e.v.norm() + e.a.norm() + e.tau.norm(), 0.0);
}

TEST(DynamicsCommand, OutputEqualsTheCoreAlgorithms) {
  const auto m = human48();
  const json out = cli::run_dynamics(*m, human_state());
  const cli::NamedState s = cli::read_named_state(*m, human_state());
  core::Data d(*m);
  const Eigen::VectorXd tau = core::rnea(*m, d, s.q, s.v, s.a);
  const Eigen::VectorXd a = core::aba(*m, d, s.q, s.v, s.tau);
  const Eigen::VectorXd b = core::bias_forces(*m, d, s.q, s.v);
  const Eigen::MatrixXd M = core::crba(*m, d, s.q);
  EXPECT_EQ(out["character"], "human48");
  EXPECT_EQ(out["nv"], 48);
  EXPECT_EQ(out["fixed_base"], false);
  // order lists velocity coordinates: joint[k] for multi-DOF joints, joint for 1-DOF
  ASSERT_EQ(out["order"].size(), 48u);
  EXPECT_EQ(out["order"][0], "root[0]");
  EXPECT_EQ(out["order"][5], "root[5]");
  const int elbow = m->joint_index("l_elbow");
  EXPECT_EQ(out["order"][m->idx_v[elbow]], "l_elbow");
  EXPECT_EQ(out["order"][m->idx_v[m->joint_index("l_shoulder")] + 2], "l_shoulder[2]");
  // values keyed by joint name, in the input's shapes
  EXPECT_EQ(out["tau"]["l_elbow"].get<double>(), tau[m->idx_v[elbow]]);
  EXPECT_EQ(out["tau"]["root"].size(), 6u);
  EXPECT_EQ(out["tau"]["root"][4].get<double>(), tau[4]);
  EXPECT_EQ(out["a"]["l_shoulder"][1].get<double>(), a[m->idx_v[m->joint_index("l_shoulder")] + 1]);
  EXPECT_EQ(out["bias"]["root"][0].get<double>(), b[0]);
  ASSERT_EQ(out["M"].size(), 48u);
  for (int r = 0; r < 48; ++r) {
    ASSERT_EQ(out["M"][r].size(), 48u);
    for (int c = 0; c < 48; ++c) EXPECT_EQ(out["M"][r][c].get<double>(), M(r, c));
  }
  // and the numbers are physics: tau = M a + b for the given a
  Eigen::VectorXd tau_check = M * s.a + b;
  EXPECT_NEAR(out["tau"]["l_elbow"].get<double>(), tau_check[m->idx_v[elbow]], 1e-10);
  // the floating base alone: no torque on the root means the root's six tau are M_b a + b_b
  EXPECT_GT(std::abs(out["tau"]["root"][4].get<double>()), 1.0);
}

TEST(DynamicsCommand, WeldedRootFixesTheFigure) {
  // --fixed-base on a free-root figure: the root's six coordinates are gone, and a standing
  // figure at rest needs no root force, only joint torques against gravity
  const auto welded = core::weld_root(human48());
  const json out = cli::run_dynamics(*welded, json::object());
  EXPECT_EQ(out["nv"], 42);
  EXPECT_EQ(out["fixed_base"], true);
  EXPECT_FALSE(out["tau"].contains("root"));
  EXPECT_EQ(out["order"].size(), 42u);
  // at neutral the figure is its own mirror image: both hips hold the same moment about x
  // (the feet's centres of mass lie in front of the ankles)
  const double l = out["tau"]["l_hip"][0].get<double>(), r = out["tau"]["r_hip"][0].get<double>();
  EXPECT_NEAR(l, r, 1e-12);
  EXPECT_GT(std::abs(l), 1e-3);
  // the root given in the state is rejected: it is fixed now
  try {
    cli::read_named_state(*welded, {{"q", {{"root", {0, 0, 0, 1, 0, 0, 0}}}}});
    ADD_FAILURE() << "expected a RequestError";
  } catch (const cli::RequestError& e) {
    EXPECT_NE(std::string(e.what()).find("/q/root: joint 'root' is fixed"), std::string::npos)
        << e.what();
  }
}

TEST(DynamicsCommand, UrdfCharacterByName) {
  const auto m = io::load_character("manipulator5").model;
  const json out = cli::run_dynamics(*m, {{"q", {{"joint2", 0.3}, {"joint3", -0.6}}}});
  EXPECT_EQ(out["nv"], 5);
  // at rest the torques are the bias, which is gravity; the slewing axis carries none
  EXPECT_EQ(out["tau"], out["bias"]);
  EXPECT_NEAR(out["tau"]["joint1"].get<double>(), 0.0, 1e-9);
  EXPECT_GT(std::abs(out["tau"]["joint2"].get<double>()), 1000.0);
  // with no torque the arm falls: gravity accelerates the boom down (negative θ̈2)
  EXPECT_LT(out["a"]["joint2"].get<double>(), 0.0);
}

// the message of the RequestError that `state` raises on the human figure
std::string error_of(const json& state) {
  try {
    cli::read_named_state(*human48(), state);
  } catch (const cli::RequestError& e) {
    return e.what();
  }
  return "";
}

TEST(DynamicsCommand, BadInputNamesTheField) {
  EXPECT_EQ(error_of(json::array()), "/: expected an object with q, v, a and tau");
  EXPECT_EQ(error_of({{"q", 3}}), "/q: expected an object keyed by joint name");
  EXPECT_EQ(error_of({{"q", {{"elbow", 0.1}}}}), "/q/elbow: unknown joint 'elbow' in 'human48'");
  EXPECT_EQ(error_of({{"v", {{"l_elbow", "fast"}}}}), "/v/l_elbow: expected a number, got string");
  EXPECT_EQ(error_of({{"tau", {{"l_elbow", nullptr}}}}),
            "/tau/l_elbow: expected a number, got null");
  EXPECT_EQ(error_of({{"a", {{"l_elbow", std::numeric_limits<double>::quiet_NaN()}}}}),
            "/a/l_elbow: number is not finite");
  EXPECT_EQ(error_of({{"v", {{"l_shoulder", {1, 2}}}}}),
            "/v/l_shoulder: expected 3 numbers [x, y, z] (child frame), got an array of 2");
  EXPECT_EQ(
      error_of({{"a", {{"root", {1, 2, 3}}}}}),
      "/a/root: expected 6 numbers [ωx, ωy, ωz, vx, vy, vz] (child frame), got an array of 3");
  EXPECT_EQ(error_of({{"q", {{"root", {0, 0, 0, 1, 0, 0}}}}}),
            "/q/root: expected 7 numbers [x, y, z, w, qx, qy, qz], got an array of 6");
  EXPECT_EQ(error_of({{"q", {{"root", {0, 0, 0, 1, 0, "x", 0}}}}}),
            "/q/root/5: expected a number, got string");
  EXPECT_EQ(error_of({{"q", {{"l_shoulder", {1, 2, 3}}}}}),
            "/q/l_shoulder: expected an array of 4 numbers [w, x, y, z]");
  EXPECT_NE(
      error_of({{"q", {{"l_shoulder", {1, 1, 0, 0}}}}}).find("/q/l_shoulder: quaternion norm is"),
      std::string::npos);
  EXPECT_NE(error_of({{"q", {{"root", {0, 0, 0, 2, 0, 0, 0}}}}})
                .find("/q/root (quaternion part): quaternion norm is 2"),
            std::string::npos);
  EXPECT_EQ(error_of({{"q", {{"l_elbow", {0.1}}}}}), "/q/l_elbow: expected a number, got array");
}

}  // namespace
