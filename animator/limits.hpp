// Budgets on every size a user controls in a session, so that no session can take the machine:
// the length of a clip (seconds, frames, numbers), keys, edit layers and undo memory. The server
// sets them from `pindrag serve` (docs/protocol.md, "Limits"); every refusal names the limit and
// the setting that changes it.
//
// The defaults, and why:
// - 1 hour and 216,000 frames per clip (an hour at 60 fps, half an hour of 120 fps capture):
//   longer than any take a posing tool edits; capture sessions come in takes of minutes.
// - 2^24 numbers per clip (frames × coordinates; 128 MiB as doubles): one clip of a 31-joint
//   capture skeleton (127 coordinates) holds 132,000 frames; its session file stays under 400 MB.
// - 10,000 keys: a key every third of a second over the whole hour.
// - 64 edit layers: each is one drag during playback; baking folds them into the clip.
// - 64 MiB of undo history per session: thousands of entries now that entries hold differences;
//   the oldest are dropped first, and the newest is always kept.
// Layers are bounded by number, and each by the clip's frames; sessions loaded from a file are
// restored whole even when they exceed the budgets (they were accepted under other settings).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "io/clip_budget.hpp"

namespace animator {

struct Limits {
  double max_clip_seconds = 3600;
  std::int64_t max_clip_frames = 216'000;
  std::int64_t max_clip_values = std::int64_t{1} << 24;
  int max_keys = 10'000;
  int max_layers = 64;
  std::size_t max_undo_bytes = std::size_t{64} << 20;
};

/// The settings that change each limit, as `pindrag serve` spells them.
inline constexpr const char* kMaxClipSecondsSetting = "pindrag serve --max-clip-seconds";
inline constexpr const char* kMaxClipFramesSetting = "pindrag serve --max-clip-frames";
inline constexpr const char* kMaxClipValuesSetting = "pindrag serve --max-clip-values";
inline constexpr const char* kMaxKeysSetting = "pindrag serve --max-keys";
inline constexpr const char* kMaxLayersSetting = "pindrag serve --max-layers";
inline constexpr const char* kMaxUndoBytesSetting = "pindrag serve --max-undo-bytes";

/// The clip limits as a reader's budget (io/clip_budget.hpp), each naming its setting.
io::ClipBudget clip_budget(const Limits& limits);

/// Empty when `limits` are usable (every limit > 0, the seconds finite), else which is not,
/// named by its setting.
std::string check_limits(const Limits& limits);

}  // namespace animator
