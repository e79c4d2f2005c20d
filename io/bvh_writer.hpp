// The conservative BVH writer, for any Model and Clip.
//
// One ROOT with OFFSET 0 0 0 and 6 channels (positions first), every other joint 3 rotation
// channels, or 6 when its translation moves (a free or prismatic joint; then OFFSET is 0 0 0 and
// the position channels carry the whole translation, so readers that add and readers that replace
// agree). Fixed links fold into their parent's offset; a fixed link with no moving joint below it
// becomes an End Site, and a leaf joint without one gets `End Site { OFFSET 0 0 0 }` (not when
// the layout of an imported file names it, so files without End Sites stay that way). Each
// written joint's rotation is its link frame relative to its written parent, so any Model works,
// whatever its rest placements. Tabs, `\n`, exact-case keywords, values in fixed notation with 6
// decimals, no exponents, no "-0.000000"; `Frame Time` in its shortest exact decimal form with at
// least 7 significant digits. Euler angles (io/bvh_euler.hpp) are unwrapped across frames (the
// equivalent triple closest to the previous frame). Names are sanitized to [A-Za-z0-9_]+ (other
// bytes become '_') and made unique with "_2", "_3", ...
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <string_view>

#include "io/bvh_document.hpp"

namespace io {

struct BvhLayout;  // io/bvh_import.hpp

struct BvhExportOptions {
  /// Rotation order of every joint, e.g. "ZXY". Empty: the layout's order per joint (its rotation
  /// channels in file order, missing axes appended in X, Y, Z order), else "ZXY".
  std::optional<std::string> rotation_order;
  /// Metres per file unit (file value = metres / scale). Empty: the layout's scale, else 1.
  std::optional<double> scale;
  /// The layout of an imported file: its names, channel orders and scale are used by link name.
  const BvhLayout* layout = nullptr;
  std::function<void(double)> progress;  // fraction done in [0, 1]
};

/// The document the writer would write for a model and a clip.
/// @throws std::invalid_argument when the clip does not fit the model or an option is invalid
BvhDocument make_bvh_document(const Model& model,
                              const Clip& clip,
                              const BvhExportOptions& options = {});

/// BVH text of a document: tabs, `\n`, exact-case keywords, %.6f-style values (see above).
/// @throws std::invalid_argument when the document is inconsistent (value count, order of nodes)
///         or holds what parse_bvh would refuse (a value beyond kMaxBvhMagnitude, more frames or
///         joints than the limits), so that whatever is written reads back
std::string format_bvh(const BvhDocument& doc);

/// format_bvh(make_bvh_document(...)).
std::string write_bvh(const Model& model, const Clip& clip, const BvhExportOptions& options = {});
/// Writes write_bvh(...) to `path` atomically: a temporary file in the same folder, fsync, rename
/// over `path`, fsync of the folder.
/// @throws std::invalid_argument (see above) or std::system_error naming the path
void save_bvh_file(const Model& model,
                   const Clip& clip,
                   const std::string& path,
                   const BvhExportOptions& options = {});

/// The value of a units option as BvhExportOptions::scale: "m" (metres: 1), "cm" (centimetres:
/// 0.01) or "source" (empty: the layout's unit, metres without one); case-insensitive.
/// @throws std::invalid_argument "<option>: '<value>' (rule: one of m, cm, source)"
std::optional<double> parse_bvh_units(std::string_view value, std::string_view option);
/// The value of a rotation order option as BvhExportOptions::rotation_order: one of the six
/// orders ("XYZ", ..., "ZYX", any case; returned in upper case) for every joint, or "source"
/// (empty: each joint's order in the layout, ZXY without one).
/// @throws std::invalid_argument "<option>: '<value>' (rule: one of XYZ, ..., source)"
std::optional<std::string> parse_bvh_order(std::string_view value, std::string_view option);

/// `name` with every byte outside [A-Za-z0-9_] replaced by '_' ("joint" when empty).
std::string sanitize_bvh_name(std::string_view name);

}  // namespace io
