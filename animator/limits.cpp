#include "animator/limits.hpp"

#include <cmath>

namespace animator {

io::ClipBudget clip_budget(const Limits& limits) {
  io::ClipBudget b;
  b.max_seconds = limits.max_clip_seconds;
  b.max_frames = limits.max_clip_frames;
  b.max_values = limits.max_clip_values;
  b.seconds_setting = kMaxClipSecondsSetting;
  b.frames_setting = kMaxClipFramesSetting;
  b.values_setting = kMaxClipValuesSetting;
  return b;
}

std::string check_limits(const Limits& l) {
  const auto rule = [](const char* setting, const char* what) {
    return std::string(setting) + ": " + what;
  };
  if (!(l.max_clip_seconds > 0) || !std::isfinite(l.max_clip_seconds))
    return rule(kMaxClipSecondsSetting, "must be a finite number > 0");
  if (l.max_clip_frames < 1) return rule(kMaxClipFramesSetting, "must be at least 1");
  if (l.max_clip_values < 1) return rule(kMaxClipValuesSetting, "must be at least 1");
  if (l.max_keys < 1) return rule(kMaxKeysSetting, "must be at least 1");
  if (l.max_layers < 1) return rule(kMaxLayersSetting, "must be at least 1");
  if (l.max_undo_bytes < 1) return rule(kMaxUndoBytesSetting, "must be at least 1");
  return {};
}

}  // namespace animator
