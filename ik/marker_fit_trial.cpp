// fit_trajectories: a whole trial, frame after frame, in one pass or in chunks on several
// threads (ik/marker_fit.hpp).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <thread>

#include "core/configuration.hpp"
#include "ik/marker_fit.hpp"

namespace ik {

namespace {

// marker error sums (in `mean`, divided in finish_stats) and maxima of the last fit
void accumulate(const MarkerFitter& fitter,
                const std::uint8_t* present,
                std::vector<MarkerStats>& stats) {
  const Eigen::VectorXd& e = fitter.errors();
  for (int j = 0; j < e.size(); ++j) {
    if (!present[j]) continue;
    stats[j].mean += e[j];
    stats[j].max = std::max(stats[j].max, e[j]);
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

// Fits frames [first, last) into r (r.clip.frames holds every fitted pose, the lead-in's too,
// which only this pass writes), starting `lead_in` frames earlier from the rest pose placed on
// the markers; the kept frames' marker sums and maxima go to `stats`, and `done` counts them.
void fit_range(const core::Model& model,
               const MarkerSet& set,
               const MarkerTrajectories& t,
               const MarkerFitSettings& settings,
               int first,
               int last,
               int lead_in,
               std::vector<Eigen::VectorXd>& frames,
               std::vector<FrameFit>& fits,
               std::vector<MarkerStats>& stats,
               std::atomic<int>& done) {
  MarkerFitter fitter(model, set, settings);
  Eigen::VectorXd q = core::rest_configuration(model);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
  const int start = std::max(0, first - lead_in);
  // the lead-in's poses: the previous chunk's last frames, kept aside (that chunk writes them)
  std::vector<Eigen::VectorXd> lead(first - start);
  const auto pose = [&](int f) -> Eigen::VectorXd& {
    return f < first ? lead[f - start] : frames[f];
  };
  bool started = false;
  for (int f = start; f < last; ++f) {
    const core::Vector3* targets = t.frame_positions(f);
    const std::uint8_t* present = t.frame_present(f);
    const int n = fitter.count_present(present);
    FrameFit fit{0.0, n, 0, true};
    // a frame too poorly observed to fit, and the warm start of the next one, continue the motion
    // of the last two frames: q_f = q_{f−1} ⊕ (q_{f−1} ⊖ q_{f−2}) (constant velocity on the
    // manifold), with the frames wherever this pass keeps them
    const auto previous = [&](Eigen::VectorXd& out) {
      if (f - start >= 2) {
        core::difference(model, pose(f - 2), pose(f - 1), v);
        core::integrate(model, pose(f - 1), v, 1.0, out);
      } else if (f - start == 1) {
        out = pose(f - 1);
      }
    };
    if (n < settings.min_markers ||
        fitter.count_root_present(present) < settings.min_root_markers) {
      if (started) previous(q);
    } else {
      if (!started) fitter.place_root(targets, present, q);
      // warm start: the previous pose, moved on by the previous frame's velocity
      if (started && settings.predict && f - start >= 2) previous(q);
      const int iterations = started ? settings.max_iterations : settings.first_frame_iterations;
      fit = fitter.fit(targets, present, q, iterations);
      if (f >= first) accumulate(fitter, present, stats);
      started = true;
    }
    pose(f) = q;
    if (f >= first) {
      fits[f] = fit;
      done.fetch_add(1, std::memory_order_relaxed);
    }
  }
}

}  // namespace

MarkerFitResult fit_trajectories(const core::Model& model,
                                 const MarkerSet& set,
                                 const MarkerTrajectories& trajectories,
                                 const MarkerFitSettings& settings,
                                 const std::function<void(double)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  const MarkerTrajectories& t = trajectories;
  MarkerFitResult r;
  r.clip.frame_time = t.rate_hz > 0 ? 1.0 / t.rate_hz : 1.0 / 30.0;
  r.clip.frames.assign(t.frames, core::rest_configuration(model));
  r.frames.assign(t.frames, FrameFit{});
  r.markers.assign(t.markers, MarkerStats{});
  int threads = settings.threads > 0 ? settings.threads
                                     : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::max(1, std::min(threads, t.frames / kMinChunkFrames));
  std::vector<std::vector<MarkerStats>> stats(threads,
                                              std::vector<MarkerStats>(t.markers, MarkerStats{}));
  std::atomic<int> done{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  const auto chunk = [&](int k) {
    try {
      fit_range(model, set, t, settings, k * t.frames / threads, (k + 1) * t.frames / threads,
                k == 0 ? 0 : kChunkLeadIn, r.clip.frames, r.frames, stats[k], done);
    } catch (...) {
      std::lock_guard lock(failure_mutex);
      failure = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  for (int k = 0; k < threads; ++k) workers.emplace_back(chunk, k);
  // this thread reports the progress of all chunks until they are done
  while (progress && done.load() < t.frames) {
    {
      std::lock_guard lock(failure_mutex);
      if (failure) break;
    }
    progress(static_cast<double>(done.load()) / t.frames);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (std::thread& w : workers) w.join();
  if (failure) std::rethrow_exception(failure);
  if (progress) progress(1.0);
  for (const std::vector<MarkerStats>& s : stats) {
    for (int j = 0; j < t.markers; ++j) {
      r.markers[j].mean += s[j].mean;
      r.markers[j].max = std::max(r.markers[j].max, s[j].max);
    }
  }
  finish_stats(t, r);
  const double us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  r.microseconds_per_frame = t.frames > 0 ? us / t.frames : 0.0;
  return r;
}

}  // namespace ik
