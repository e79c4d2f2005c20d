#include "animator/clip_markers.hpp"

#include <atomic>
#include <cmath>
#include <stdexcept>

namespace animator {

namespace {
std::atomic<std::uint64_t> next_revision{1};
}  // namespace

std::string check_clip_markers(const core::Model& model,
                               const ik::MarkerSet& set,
                               const ik::MarkerTrajectories& measured) {
  if (set.size() == 0) return "has no markers";
  if (const std::string e = ik::check_marker_set(model, set); !e.empty()) return e;
  if (measured.markers != set.size()) {
    return "measured has " + std::to_string(measured.markers) + " columns for " +
           std::to_string(set.size()) + " markers";
  }
  if (!(measured.rate_hz > 0) || !std::isfinite(measured.rate_hz))
    return "rate must be positive and finite";
  if (measured.frames < 1) return "has no frames";
  const std::size_t samples =
      static_cast<std::size_t>(measured.frames) * static_cast<std::size_t>(measured.markers);
  if (measured.positions.size() != samples || measured.present.size() != samples)
    return "measured holds " + std::to_string(measured.positions.size()) + " samples for " +
           std::to_string(samples);
  for (std::size_t k = 0; k < samples; ++k) {
    if (measured.present[k] && !measured.positions[k].allFinite()) {
      return "frame " + std::to_string(k / set.size()) + ", marker " +
             set.markers[k % set.size()].name + ": position is not finite";
    }
  }
  return {};
}

std::shared_ptr<const ClipMarkers> make_clip_markers(const core::Model& model,
                                                     ik::MarkerSet set,
                                                     ik::MarkerTrajectories measured) {
  if (const std::string e = check_clip_markers(model, set, measured); !e.empty())
    throw std::invalid_argument(e);
  auto out = std::make_shared<ClipMarkers>();
  out->set = std::move(set);
  out->measured = std::move(measured);
  out->revision = next_revision.fetch_add(1, std::memory_order_relaxed);
  return out;
}

std::string check_markers_fit_clip(const ClipMarkers& markers, const core::Clip& clip) {
  if (markers.measured.frames != clip.size()) {
    return "markers have " + std::to_string(markers.measured.frames) + " frames, the clip " +
           std::to_string(clip.size());
  }
  const double frame_time = 1.0 / markers.measured.rate_hz;
  if (std::abs(frame_time - clip.frame_time) > 1e-9 * clip.frame_time) {
    return "markers at " + std::to_string(markers.measured.rate_hz) +
           " Hz, the clip at another rate";
  }
  return {};
}

}  // namespace animator
