#include "cli/fit_report.hpp"

namespace cli {

namespace {

nlohmann::json marker_table(const FitReportInput& in) {
  nlohmann::json markers = nlohmann::json::object();
  for (int j = 0; j < in.set->size(); ++j) {
    const ik::Marker& m = in.set->markers[j];
    const ik::MarkerStats& s = in.result->markers[j];
    markers[m.name] = {{"link", in.model->link_name[m.link]},
                       {"mean", s.mean},
                       {"max", s.max},
                       {"missing", s.missing},
                       {"offset", {m.offset.x(), m.offset.y(), m.offset.z()}}};
  }
  return markers;
}

nlohmann::json scale_table(const FitReportInput& in) {
  nlohmann::json scales = nlohmann::json::object();
  for (int k = 1; k < in.model->njoints; ++k) {
    scales[in.model->link_name[k]] = in.scales.empty() ? 1.0 : in.scales[k];
  }
  return scales;
}

}  // namespace

nlohmann::json fit_report(const FitReportInput& in) {
  const ik::MarkerFitResult& r = *in.result;
  nlohmann::json frames = nlohmann::json::array();
  int flagged = 0, second_starts = 0, second_starts_kept = 0;
  for (const ik::FrameFit& f : r.frames) {
    nlohmann::json frame{{"rms", f.rms}, {"present", f.present}, {"flagged", f.flagged}};
    if (f.second_start) frame["second_start"] = f.second_start_kept ? "kept" : "tried";
    frames.push_back(std::move(frame));
    flagged += f.flagged ? 1 : 0;
    second_starts += f.second_start ? 1 : 0;
    second_starts_kept += f.second_start_kept ? 1 : 0;
  }
  return {{"character", in.model->name},
          {"mean_error", r.mean_error},
          {"frames_fitted", static_cast<int>(r.frames.size()) - flagged},
          {"frames_flagged", flagged},
          {"second_starts", {{"tried", second_starts}, {"kept", second_starts_kept}}},
          {"markers", marker_table(in)},
          {"not_in_trial", in.not_in_trial},
          {"frames", frames},
          {"scales", scale_table(in)},
          {"calibration_rms", in.calibration_rms},
          {"calibration_us", in.calibration_us},
          {"us_per_frame", r.microseconds_per_frame},
          {"frame_time", r.clip.frame_time}};
}

}  // namespace cli
