// The liberal BVH reader: text into a BvhDocument (io/bvh_document.hpp).
//
// Whitespace-tokenized, so CRLF, tabs, blank lines, trailing blanks, `{` on the joint line and a
// UTF-8 byte-order mark are fine; keywords and channel names match without regard to case. Joint
// names are the text after ROOT/JOINT up to `{` or the end of the line (words joined by one
// space).
//
// Rejected, each with a ModelError "<file>: line <n>: <what> (rule: <rule>)": a missing
// HIERARCHY, ROOT or MOTION, a second ROOT (one skeleton per file), a joint without OFFSET or
// CHANNELS, an unknown channel, a channel listed twice in one joint, a CHANNELS count that
// disagrees with the names that follow, duplicate joint names, a motion line whose value count is
// not the sum of all CHANNELS, fewer motion lines than `Frames:` declares, more than one extra
// line after them, a value that is not a number, NaN or infinite, or beyond kMaxBvhMagnitude,
// control characters (binary data) in the hierarchy, and anything beyond the limits in
// io/bvh_document.hpp. Tolerated with a warning: exactly one complete extra motion line after the
// declared frames (boxing_toes_zxy.bvh declares 3069 frames and holds 3070 lines); it is ignored,
// so the clip has the declared number of frames, as three.js and assimp read it.
//
// Budget: a document whose `Frames:` and `Frame Time:` declare a clip beyond `budget`
// (io/clip_budget.hpp; frames × the larger of the file's channels and the imported
// configuration's coordinates) is refused when the header is read, before any frame is stored.
//
// Memory: nothing is reserved from what the header claims. Frame storage is reserved only after
// the first motion line, for at most as many frames as the remaining bytes can hold at that
// line's length, so a 10⁹-frame header over a short file allocates nothing large.
#pragma once

#include <string>
#include <string_view>

#include "io/bvh_document.hpp"
#include "io/clip_budget.hpp"

namespace io {

/// Parses BVH text; `source_name` starts every message.
/// @throws ModelError "<source>: line <n>: <what> (rule: ...)", also for a clip over `budget`
BvhDocument parse_bvh(std::string_view text,
                      const std::string& source_name,
                      const ClipBudget& budget = {});

}  // namespace io
