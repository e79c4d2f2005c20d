// Marker fitting (ik/marker_fit.hpp): frames fitted per second on the CMU trial cmu_85_02
// (41 markers, 120 Hz, 810 frames) with the bundled marker set on human48, calibrated once on
// the first second; single-threaded. Target (issue 16): ≥ 2,000 frames/s.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>

#include "animator/marker_trial.hpp"
#include "cli/marker_set_file.hpp"
#include "core/human_figure.hpp"
#include "ik/marker_calibration.hpp"

namespace {

std::string trial_path() {
  const char* env = std::getenv("PINDRAG_DATA_DIR");
  return std::string(env ? env : PINDRAG_DATA_DIR) + "/c3d/cmu_85_02.c3d";
}

void BM_MarkerFit(benchmark::State& state) {
  if (!std::filesystem::exists(trial_path())) {
    state.SkipWithError("cmu_85_02.c3d not found (set PINDRAG_DATA_DIR)");
    return;
  }
  const auto model = core::build_human_figure();
  const ik::MarkerSet set =
      cli::read_marker_set_file(animator::bundled_marker_set_path(*model), *model);
  const animator::TrialMarkers tm = animator::markers_from_c3d(io::read_c3d(trial_path()), set);
  ik::MarkerFitSettings fs;
  fs.enforce_ranges = state.range(0) != 0;
  const ik::CalibrationResult c = ik::calibrate_markers(model, set, tm.trajectories, fs);
  fs.threads = static_cast<int>(state.range(1));
  double mean_error = 0;
  for (auto _ : state) {
    const ik::MarkerFitResult r = ik::fit_trajectories(*c.model, c.set, tm.trajectories, fs);
    mean_error = r.mean_error;
    benchmark::DoNotOptimize(r.clip.frames.data());
  }
  state.SetItemsProcessed(state.iterations() * tm.trajectories.frames);  // items = frames
  state.counters["mean_error_mm"] = mean_error * 1000;
}
// wall time: with threads the work is spread over cores
BENCHMARK(BM_MarkerFit)
    ->ArgNames({"ranges", "threads"})
    ->Args({1, 1})
    ->Args({0, 1})
    ->Args({1, 2})
    ->Args({0, 2})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
