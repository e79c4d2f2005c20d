// Synthetic marker trials for the marker-fitting tests: a known human motion, its markers by
// forward kinematics, noise and dropped samples.
#pragma once

#include <cmath>
#include <numbers>
#include <random>

#include "core/clip.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"
#include "ik/marker_fit.hpp"

namespace marker_fit_test {

/// Smooth motion of the human figure within its ranges: root sway and turn, hips, knees,
/// shoulders, elbows and the trunk, sinusoids of different periods.
inline core::Clip smooth_motion(const core::Model& m, int frames, double rate) {
  core::Clip c;
  c.frame_time = 1.0 / rate;
  const double tau = 2 * std::numbers::pi;
  auto rot = [](double a, const core::Vector3& axis) {
    return core::Quaternion(Eigen::AngleAxisd(a, axis));
  };
  for (int f = 0; f < frames; ++f) {
    const double t = f * c.frame_time;
    Eigen::VectorXd q = core::rest_configuration(m);
    q.segment<3>(0) << 0.1 * std::sin(tau * 0.3 * t), 0.03 * std::sin(tau * t), 0.2 * t;
    core::set_quaternion_at(q, 3, rot(0.3 * std::sin(tau * 0.2 * t), core::Vector3::UnitY()));
    auto set = [&](const char* link, const core::Quaternion& r) {
      core::set_quaternion_at(q, m.idx_q[m.link_index(link)], r);
    };
    auto angle = [&](const char* link, double a) { q[m.idx_q[m.link_index(link)]] = a; };
    set("l_thigh", rot(-0.5 * std::sin(tau * 0.7 * t), core::Vector3::UnitX()));
    set("r_thigh", rot(0.5 * std::sin(tau * 0.7 * t), core::Vector3::UnitX()));
    angle("l_shank", 0.6 + 0.4 * std::sin(tau * 0.7 * t));
    angle("r_shank", 0.6 - 0.4 * std::sin(tau * 0.7 * t));
    set("l_uarm", rot(0.5 * std::sin(tau * 0.5 * t), core::Vector3::UnitX()) *
                      rot(-0.3, core::Vector3::UnitZ()));
    set("r_uarm", rot(-0.5 * std::sin(tau * 0.5 * t), core::Vector3::UnitX()) *
                      rot(0.3, core::Vector3::UnitZ()));
    angle("l_farm", 0.8 + 0.3 * std::sin(tau * 0.9 * t));
    angle("r_farm", 0.8 + 0.3 * std::cos(tau * 0.9 * t));
    set("abdomen", rot(0.15 * std::sin(tau * 0.4 * t), core::Vector3::UnitX()));
    c.frames.push_back(q);
  }
  return c;
}

/// The markers of `set` along `clip`, with Gaussian noise (sigma, m) and a fraction dropped.
inline ik::MarkerTrajectories markers_of(const core::Model& m,
                                         const ik::MarkerSet& set,
                                         const core::Clip& clip,
                                         double sigma,
                                         double dropped,
                                         unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ik::MarkerTrajectories t;
  t.rate_hz = 1.0 / clip.frame_time;
  t.frames = clip.size();
  t.markers = set.size();
  core::Data d(m);
  for (const Eigen::VectorXd& q : clip.frames) {
    core::forward_kinematics(m, d, q);
    for (const ik::Marker& mk : set.markers) {
      const bool present = u(rng) >= dropped;
      const core::Vector3 e(noise(rng), noise(rng), noise(rng));
      t.positions.push_back(present ? core::Vector3(d.X_W[mk.link] * mk.offset + e)
                                    : core::Vector3::Zero());
      t.present.push_back(present ? 1 : 0);
    }
  }
  return t;
}

}  // namespace marker_fit_test
