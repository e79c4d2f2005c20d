#include "io/clip_budget.hpp"

#include <cmath>
#include <sstream>

namespace io {
namespace {

std::string shown(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

std::string set_by(const std::string& setting) {
  return setting.empty() ? std::string() : " (set by " + setting + ")";
}

}  // namespace

std::string clip_budget_refusal(const ClipBudget& budget,
                                std::int64_t frames,
                                double frame_time,
                                std::int64_t per_frame) {
  const double seconds = frames < 2 ? 0.0 : static_cast<double>(frames - 1) * frame_time;
  // a clip of exactly the limit passes despite the rounding of (frames − 1) × frame_time
  if (seconds > budget.max_seconds * (1 + 1e-12)) {
    return shown(seconds) + " s exceed the limit of " + shown(budget.max_seconds) + " s per clip" +
           set_by(budget.seconds_setting);
  }
  if (frames > budget.max_frames) {
    return std::to_string(frames) + " frames exceed the limit of " +
           std::to_string(budget.max_frames) + " frames per clip" + set_by(budget.frames_setting);
  }
  // frames × per_frame without overflow: compare by division
  if (per_frame > 0 && frames > budget.max_values / per_frame) {
    const double values = static_cast<double>(frames) * static_cast<double>(per_frame);
    return std::to_string(frames) + " frames × " + std::to_string(per_frame) +
           " numbers = " + shown(values) + " numbers exceed the limit of " +
           std::to_string(budget.max_values) + " numbers per clip" + set_by(budget.values_setting);
  }
  return {};
}

}  // namespace io
