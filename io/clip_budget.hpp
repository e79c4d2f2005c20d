// The budget of one clip read from a file: how long it may last, how many frames and how many
// numbers (frames × numbers per frame) it may hold. Readers check the clip's declared size
// against it when they learn it (a BVH's `Frames:` header, a glTF animation's key span) and refuse
// the file before storing any frame. The default budget is unbounded; the readers' own format
// limits still apply.
#pragma once

#include <cstdint>
#include <limits>
#include <string>

namespace io {

struct ClipBudget {
  double max_seconds = std::numeric_limits<double>::infinity();
  std::int64_t max_frames = std::numeric_limits<std::int64_t>::max();
  std::int64_t max_values = std::numeric_limits<std::int64_t>::max();
  // how each limit is changed, shown in its refusal ("pindrag serve --max-clip-frames"); empty:
  // nothing is shown
  std::string seconds_setting, frames_setting, values_setting;
};

/// Empty when a clip of `frames` frames, `frame_time` seconds apart, with `per_frame` numbers
/// each, fits the budget; else why not, naming the limit and its setting:
/// "990001 frames exceed the limit of 216000 frames per clip (set by pindrag serve
/// --max-clip-frames)". The length is (frames − 1) × frame_time, as core::Clip::duration.
std::string clip_budget_refusal(const ClipBudget& budget,
                                std::int64_t frames,
                                double frame_time,
                                std::int64_t per_frame);

}  // namespace io
