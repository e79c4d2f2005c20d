// fit_trajectories: a whole trial, frame after frame (ik/marker_fit.hpp).
#include <algorithm>
#include <chrono>

#include "core/configuration.hpp"
#include "ik/marker_fit.hpp"

namespace ik {

namespace {

// A frame too poorly observed to fit: continue the motion of the last two frames,
// q_f = q_{f−1} ⊕ (q_{f−1} ⊖ q_{f−2}) (constant velocity on the manifold).
void extrapolate(const core::Model& model,
                 const std::vector<Eigen::VectorXd>& frames,
                 int f,
                 Eigen::VectorXd& v,
                 Eigen::VectorXd& q) {
  if (f >= 2) {
    core::difference(model, frames[f - 2], frames[f - 1], v);
    core::integrate(model, frames[f - 1], v, 1.0, q);
  } else if (f == 1) {
    q = frames[0];
  }
}

void accumulate(const MarkerFitter& fitter, const std::uint8_t* present, MarkerFitResult& r) {
  const Eigen::VectorXd& e = fitter.errors();
  for (int j = 0; j < e.size(); ++j) {
    if (!present[j]) continue;
    r.markers[j].mean += e[j];  // a sum until finish_stats
    r.markers[j].max = std::max(r.markers[j].max, e[j]);
  }
}

void finish_stats(const MarkerTrajectories& t, MarkerFitResult& r) {
  std::vector<int> fitted(t.markers, 0);
  for (int f = 0; f < t.frames; ++f) {
    const std::uint8_t* present = t.frame_present(f);
    for (int j = 0; j < t.markers; ++j) {
      if (!present[j]) ++r.markers[j].missing;
      if (present[j] && !r.frames[f].flagged) ++fitted[j];
    }
  }
  double sum = 0;
  int samples = 0;
  for (int j = 0; j < t.markers; ++j) {
    sum += r.markers[j].mean;
    samples += fitted[j];
    r.markers[j].mean = fitted[j] > 0 ? r.markers[j].mean / fitted[j] : 0.0;
  }
  r.mean_error = samples > 0 ? sum / samples : 0.0;
}

}  // namespace

MarkerFitResult fit_trajectories(const core::Model& model,
                                 const MarkerSet& set,
                                 const MarkerTrajectories& trajectories,
                                 const MarkerFitSettings& settings,
                                 const std::function<void(double)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  MarkerFitter fitter(model, set, settings);
  const MarkerTrajectories& t = trajectories;
  MarkerFitResult r;
  r.clip.frame_time = t.rate_hz > 0 ? 1.0 / t.rate_hz : 1.0 / 30.0;
  Eigen::VectorXd q = core::rest_configuration(model);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
  r.clip.frames.assign(t.frames, q);
  r.frames.assign(t.frames, FrameFit{});
  r.markers.assign(t.markers, MarkerStats{});
  bool started = false;
  for (int f = 0; f < t.frames; ++f) {
    const core::Vector3* targets = t.frame_positions(f);
    const std::uint8_t* present = t.frame_present(f);
    const int n = fitter.count_present(present);
    if (n < settings.min_markers ||
        fitter.count_root_present(present) < settings.min_root_markers) {
      if (started) extrapolate(model, r.clip.frames, f, v, q);
      r.frames[f] = FrameFit{0.0, n, 0, true};
    } else {
      if (!started) fitter.place_root(targets, present, q);
      // warm start: the previous pose, moved on by the previous frame's velocity
      if (started && settings.predict && f >= 2) extrapolate(model, r.clip.frames, f, v, q);
      const int iterations = started ? settings.max_iterations : settings.first_frame_iterations;
      r.frames[f] = fitter.fit(targets, present, q, iterations);
      accumulate(fitter, present, r);
      started = true;
    }
    r.clip.frames[f] = q;
    if (progress && (f % 64 == 0 || f + 1 == t.frames)) progress((f + 1.0) / t.frames);
  }
  finish_stats(t, r);
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  r.microseconds_per_frame = t.frames > 0 ? us / t.frames : 0.0;
  return r;
}

}  // namespace ik
