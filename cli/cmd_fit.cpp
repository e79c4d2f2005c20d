// `pindrag fit TRIAL.c3d --character human48 [--markers SET.json] [--static a:b] -o OUT
// [--report REPORT.json] [--scaled-character OUT.json]`: marker fitting (docs/marker-fitting.md).
// The marker offsets and segment scales are calibrated on the static range, then every frame is
// fitted (ik/marker_calibration.hpp, ik/marker_fit.hpp) and the motion is written as a clip.
#include <chrono>
#include <filesystem>
#include <iostream>

#include "animator/marker_trial.hpp"
#include "cli/clip_file.hpp"
#include "cli/commands.hpp"
#include "cli/fit_report.hpp"
#include "cli/fit_report_page.hpp"
#include "cli/json_fields.hpp"
#include "cli/marker_set_file.hpp"
#include "cli/progress_bar.hpp"
#include "ik/marker_calibration.hpp"
#include "io/atomic_file.hpp"
#include "io/bundled_characters.hpp"
#include "io/character_json.hpp"

namespace cli {

namespace {

struct FitArgs {
  std::string trial, character = "human48", markers, static_range, out, report, report_html, scaled;
  bool no_ranges = false;
  double restart_rms = ik::MarkerFitSettings{}.restart_rms;
  int threads = 1;  // the trial's fit: 0 = one per core
};

// "--static a:b" (frames, b exclusive), "all" or "none"; empty: the first second.
bool parse_static(const std::string& text, int frames, ik::CalibrationSettings& s) {
  if (text.empty()) return true;
  if (text == "none") return false;
  if (text == "all") {
    s.first_frame = 0;
    s.last_frame = frames;
    return true;
  }
  const auto colon = text.find(':');
  try {
    if (colon == std::string::npos) throw std::invalid_argument("no colon");
    size_t used_a = 0, used_b = 0;
    s.first_frame = std::stoi(text.substr(0, colon), &used_a);
    s.last_frame = std::stoi(text.substr(colon + 1), &used_b);
    if (used_a != colon || used_b != text.size() - colon - 1) throw std::invalid_argument("junk");
  } catch (const std::exception&) {
    throw RequestError("--static: '" + text + "' (rule: FIRST:LAST frames, 'all' or 'none')");
  }
  if (s.first_frame < 0 || s.last_frame <= s.first_frame || s.last_frame > frames) {
    throw RequestError("--static: '" + text +
                       "' (rule: 0 <= FIRST < LAST <= " + std::to_string(frames) + " frames)");
  }
  return true;
}

ik::MarkerSet load_marker_set(const FitArgs& a, const core::Model& model) {
  std::string path = a.markers;
  if (path.empty()) path = animator::bundled_marker_set_path(model);
  if (path.empty()) {
    throw RequestError("--markers: no bundled marker set for " + model.name +
                       " (rule: give a marker set file)");
  }
  return read_marker_set_file(path, model);
}

void write_outputs(const FitArgs& a,
                   const ClipFile& out,
                   const core::Clip& clip,
                   const nlohmann::json& report) {
  write_clip_file(a.out, out, clip);
  if (!a.report.empty()) io::write_file_atomically(a.report, report.dump(2) + "\n");
  if (!a.report_html.empty()) {
    io::write_file_atomically(a.report_html,
                              fit_report_html(report, std::filesystem::path(a.trial).filename()));
  }
  if (!a.scaled.empty()) io::save_character_json_file(*out.model, a.scaled);
}

void fit(const FitArgs& a) {
  const auto out_format = clip_format(a.out);
  if (!out_format || !writable(*out_format)) {
    throw std::invalid_argument("-o: " + a.out +
                                " (rule: the extension must be .bvh, .gltf or .glb)");
  }
  const std::shared_ptr<const core::Model> model = io::load_character(a.character).model;
  const ik::MarkerSet set = load_marker_set(a, *model);
  const io::C3dTrial trial = io::read_c3d(a.trial);
  const animator::TrialMarkers tm = animator::markers_from_c3d(trial, set);
  for (const std::string& w : trial.warnings)
    std::cerr << "warning: " << a.trial << ": " << w << "\n";
  for (const std::string& n : tm.not_in_trial)
    std::cerr << "warning: marker " << n << " is not in " << a.trial << "\n";
  ik::MarkerFitSettings fs;
  fs.enforce_ranges = !a.no_ranges;
  fs.restart_rms = a.restart_rms;
  ik::CalibrationSettings cs;
  FitReportInput in;
  ClipFile out;
  out.model = model;
  ik::MarkerSet fitted_set = set;
  const auto t0 = std::chrono::steady_clock::now();
  if (parse_static(a.static_range, tm.trajectories.frames, cs)) {
    ik::CalibrationResult c = ik::calibrate_markers(model, set, tm.trajectories, fs, cs);
    out.model = c.model;
    fitted_set = c.set;
    in.scales = c.scales;
    in.calibration_rms = c.rms_per_round;
  }
  in.calibration_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  ProgressBar bar("fit " + a.trial);
  ik::MarkerFitSettings trial_fit = fs;  // calibration stays on one thread: one path
  trial_fit.threads = a.threads;
  const ik::MarkerFitResult r = ik::fit_trajectories(
      *out.model, fitted_set, tm.trajectories, trial_fit, [&bar](double x) { bar.update(x); });
  bar.finish();
  in.model = out.model.get();
  in.set = &fitted_set;
  in.result = &r;
  in.not_in_trial = tm.not_in_trial;
  write_outputs(a, out, r.clip, fit_report(in));
  std::cerr << "pindrag fit: " << a.out << ": " << r.clip.size() << " frames, mean marker error "
            << r.mean_error * 1000 << " mm, " << r.microseconds_per_frame << " us/frame\n";
}

}  // namespace

void add_fit_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("fit",
                                 "fit a character to motion-capture markers (C3D) and write the "
                                 "motion (docs/marker-fitting.md)");
  auto args = std::make_shared<FitArgs>();
  cmd->add_option("TRIAL", args->trial, "marker trial (.c3d)")->required();
  cmd->add_option("--character", args->character, "bundled character name or character file")
      ->capture_default_str();
  cmd->add_option("--markers", args->markers,
                  "marker set (JSON); default: the bundled CMU 41-marker set of the character");
  cmd->add_option("--static", args->static_range,
                  "calibration frames FIRST:LAST (LAST excluded), 'all' or 'none'; "
                  "default: the first second");
  cmd->add_option("-o,--output", args->out, "fitted clip (.bvh, .gltf, .glb)")->required();
  cmd->add_option("--report", args->report, "fit report (JSON)");
  cmd->add_option("--report-html", args->report_html,
                  "the fit report as a page with a plot of the error over time (HTML)");
  cmd->add_option("--scaled-character", args->scaled,
                  "the calibrated (segment-scaled) character (JSON)");
  cmd->add_option("--threads", args->threads,
                  "threads fitting a long trial in chunks (default 1; 0: one per core; a chunk "
                  "needs " +
                      std::to_string(ik::kMinChunkFrames) +
                      " frames; a chunk that settles on another fit than one pass is fitted "
                      "again)")
      ->check(CLI::Range(0, 256));
  cmd->add_flag("--no-ranges", args->no_ranges,
                "let joints leave their ranges (the figure's ranges are clinical norms)");
  cmd->add_option("--restart-rms", args->restart_rms,
                  "inside the ranges, a frame fitted worse than this RMS marker error (m) is "
                  "fitted again from its unbounded fit (default 0.04; 0: never)")
      ->check(CLI::Range(0.0, 10.0));
  cmd->callback([args] {
    try {
      fit(*args);
    } catch (const std::exception& e) {
      std::cerr << "pindrag fit: " << e.what() << "\n";
      throw CLI::RuntimeError(1);
    }
  });
}

}  // namespace cli
