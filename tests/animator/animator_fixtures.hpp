// Shared by the animator tests: the human figure, a synthetic clip of it and small helpers.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "animator/session.hpp"
#include "animator/session_file.hpp"
#include "core/clip.hpp"
#include "core/configuration.hpp"
#include "core/human_figure.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace animator_test {

inline std::shared_ptr<const core::Model> human() { return fixtures::human48(); }

/// The message of the SessionError that reading the session file `j` throws ("" when none).
inline std::string session_file_error(const nlohmann::json& j) {
  try {
    animator::session_from_json(j, "test.json");
  } catch (const animator::SessionError& e) {
    return e.what();
  }
  return "";
}

inline core::Vector3 position(const animator::Session& s, const char* link) {
  return s.kinematics().X_W[s.model().link_index(link)].p;
}

inline void run(animator::Session& s, int ticks, double dt = 1.0 / 60) {
  for (int k = 0; k < ticks; ++k) s.tick(dt);
}

/// A synthetic clip of the figure: arms swinging, knees bending, the root bobbing (30 fps).
inline core::Clip swinging_clip(const core::Model& m, int frames = 60) {
  core::Clip c;
  c.frame_time = 1.0 / 30;
  for (int f = 0; f < frames; ++f) {
    const double t = f * c.frame_time;
    Eigen::VectorXd q = core::neutral_configuration(m);
    q[1] += 0.02 * std::sin(2 * std::numbers::pi * t);  // root height
    for (const char* arm : {"l_uarm", "r_uarm"}) {
      const int j = m.link_index(arm);
      core::set_quaternion_at(
          q, m.idx_q[j],
          core::Quaternion(
              Eigen::AngleAxisd(0.4 * std::sin(2 * std::numbers::pi * t), core::Vector3::UnitX())));
    }
    for (const char* knee : {"l_shank", "r_shank"})
      q[m.idx_q[m.link_index(knee)]] = 0.3 + 0.2 * std::sin(std::numbers::pi * t);
    c.frames.push_back(q);
  }
  return c;
}

}  // namespace animator_test
