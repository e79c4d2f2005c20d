// fit_trajectories: a whole trial, frame after frame, in one pass or in chunks on several
// threads (ik/marker_fit.hpp).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <optional>
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

// Where a chunk of fit_trajectories starts from, and what it leaves at its end.
struct ChunkStart {
  int lead_in = 0;  // frames fitted from the rest pose before `first` and discarded (warm-up)
  // instead of a lead-in: continue from the poses already in `frames` before `first`, as one
  // pass would (`started`: whether any of those frames was fitted rather than extrapolated)
  bool continue_previous = false;
  bool started = false;
};
struct ChunkEnd {
  bool started = false;   // some frame up to `last` was fitted
  Eigen::VectorXd seam;   // the pose this chunk fits at frame `last` (empty at the trial's end)
  Eigen::VectorXd entry;  // the lead-in's pose at frame `first` − 1 (empty without a lead-in)
};

// Fits frames [first, last) into `frames` and `fits`, warm-started frame after frame; the kept
// frames' marker sums and maxima go to `stats`, and `done` counts them. Past `last` it fits one
// more frame, kept aside in the result, so that the next chunk can be checked against it.
ChunkEnd fit_range(const core::Model& model,
                   const MarkerSet& set,
                   const MarkerTrajectories& t,
                   const MarkerFitSettings& settings,
                   int first,
                   int last,
                   const ChunkStart& from,
                   std::vector<Eigen::VectorXd>& frames,
                   std::vector<FrameFit>& fits,
                   std::vector<MarkerStats>& stats,
                   std::atomic<int>& done) {
  MarkerFitter fitter(model, set, settings);
  // a second start for poorly fitted frames inside the ranges (MarkerFitSettings::restart_rms),
  // made on first use: the unbounded fit, then the bounded one from there
  std::optional<MarkerFitter> unbounded, rebounded;
  Eigen::VectorXd warm_start, second_start;
  Eigen::VectorXd q = core::rest_configuration(model);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
  const int start = from.continue_previous ? first : std::max(0, first - from.lead_in);
  // frames that are not this chunk's own (a lead-in, the seam frame) are kept aside: other
  // chunks write them; frames before `first` when continuing are read where one pass left them
  const int history = from.continue_previous ? std::max(0, first - 2) : start;
  const int stop = std::min(t.frames, last + 1);
  std::vector<Eigen::VectorXd> aside(first - start + (stop - last));
  const auto pose = [&](int f) -> Eigen::VectorXd& {
    if (f >= first && f < last) return frames[f];
    if (f >= last) return aside[first - start + (f - last)];
    return from.continue_previous ? frames[f] : aside[f - start];
  };
  bool started = from.continue_previous && from.started;
  if (started) q = frames[first - 1];
  for (int f = start; f < stop; ++f) {
    const bool own = f >= first && f < last;
    const core::Vector3* targets = t.frame_positions(f);
    const std::uint8_t* present = t.frame_present(f);
    const int n = fitter.count_present(present);
    FrameFit fit{0.0, n, 0, true};
    // a frame too poorly observed to fit, and the warm start of the next one, continue the motion
    // of the last two frames: q_f = q_{f−1} ⊕ (q_{f−1} ⊖ q_{f−2}) (constant velocity on the
    // manifold), with the frames wherever this pass keeps them
    const auto previous = [&](Eigen::VectorXd& out) {
      if (f - history >= 2) {
        core::difference(model, pose(f - 2), pose(f - 1), v);
        core::integrate(model, pose(f - 1), v, 1.0, out);
      } else if (f - history == 1) {
        out = pose(f - 1);
      }
    };
    if (n < settings.min_markers ||
        fitter.count_root_present(present) < settings.min_root_markers) {
      if (started) previous(q);
    } else {
      if (!started) fitter.place_root(targets, present, q);
      // warm start: the previous pose, moved on by the previous frame's velocity
      if (started && settings.predict && f - history >= 2) previous(q);
      const int iterations = started ? settings.max_iterations : settings.first_frame_iterations;
      const bool may_restart = started && settings.enforce_ranges && settings.restart_rms > 0;
      if (may_restart) warm_start = q;
      fit = fitter.fit(targets, present, q, iterations);
      const MarkerFitter* used = &fitter;
      if (may_restart && fit.rms > settings.restart_rms) {
        if (!unbounded) {
          MarkerFitSettings free_joints = settings;
          free_joints.enforce_ranges = false;
          unbounded.emplace(model, set, free_joints);
          rebounded.emplace(model, set, settings);
        }
        second_start = warm_start;
        const FrameFit free_fit =
            unbounded->fit(targets, present, second_start, settings.max_iterations);
        const FrameFit again =
            rebounded->fit(targets, present, second_start, settings.max_iterations);
        fit.iterations += free_fit.iterations + again.iterations;
        fit.second_start = true;
        if (again.rms < fit.rms) {
          fit.second_start_kept = true;
          fit.rms = again.rms;
          q = second_start;
          used = &*rebounded;
        }
      }
      if (own) accumulate(*used, present, stats);
      started = true;
    }
    pose(f) = q;
    if (own) {
      fits[f] = fit;
      done.fetch_add(1, std::memory_order_relaxed);
    }
  }
  ChunkEnd end;
  end.started = started;
  if (stop > last) end.seam = pose(last);
  if (start < first) end.entry = pose(first - 1);
  return end;
}

// Whether two fits of one frame are the same solution: no coordinate apart by more than
// kSeamTolerance (rad or m). The fit of a frame can depend on where the frames before it started:
// inside the joint ranges, and wherever the markers leave a joint free (a wrist's twist, the
// lumbar/thoracic split) unless a reference weight holds it. A chunk whose lead-in settled
// elsewhere is fitted again from the end of the chunk before it.
constexpr double kSeamTolerance = 1e-6;

bool same_solution(const core::Model& model, const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  Eigen::VectorXd d(model.nv);
  core::difference(model, a, b, d);
  return d.lpNorm<Eigen::Infinity>() <= kSeamTolerance;
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
  std::vector<ChunkEnd> ends(threads);
  const auto first_of = [&](int k) { return k * t.frames / threads; };
  const auto chunk = [&](int k) {
    try {
      ChunkStart from;
      from.lead_in = k == 0 ? 0 : settings.chunk_lead_in;
      ends[k] = fit_range(model, set, t, settings, first_of(k), first_of(k + 1), from,
                          r.clip.frames, r.frames, stats[k], done);
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
  // seams, in order: a chunk whose first frame, or the frame before it (the two its warm starts
  // continue from), is not the solution the chunk before it reaches there is fitted again from
  // that chunk's end, so every chunk continues the one before it as a single pass would
  for (int k = 1; k < threads; ++k) {
    const int first = first_of(k);
    const ChunkEnd& before = ends[k - 1];
    const bool agree =
        !before.started || (before.seam.size() > 0 && ends[k].entry.size() > 0 &&
                            same_solution(model, before.seam, r.clip.frames[first]) &&
                            same_solution(model, r.clip.frames[first - 1], ends[k].entry));
    if (agree) continue;
    ++r.refitted_chunks;
    ChunkStart from;
    from.continue_previous = true;
    from.started = before.started;
    std::fill(stats[k].begin(), stats[k].end(), MarkerStats{});
    ends[k] = fit_range(model, set, t, settings, first, first_of(k + 1), from, r.clip.frames,
                        r.frames, stats[k], done);
  }
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
