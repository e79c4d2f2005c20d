// BVH (Biovision Hierarchy) in and out: a liberal reader, the import into a Model and a Clip, and
// a conservative writer for any Model. docs: ../shared/reference/ecosystem.md §1.
//
// Reading (parse_bvh): whitespace-tokenized, so CRLF, tabs, blank lines, trailing blanks, `{` on
// the joint line and a UTF-8 byte-order mark are fine; keywords and channel names match without
// regard to case. Every joint keeps its own channel list in file order. A rotation is the product
// of the elementary rotations in file order (intrinsic): channels `Zrotation Xrotation Yrotation`
// with values a, b, c give R = Rz(a) Rx(b) Ry(c). Position channels are the joint's local
// translation and replace the matching OFFSET component (Blender, MotionBuilder and assimp read
// them this way; three.js adds them to OFFSET, which agrees whenever OFFSET is zero, as it is for
// every joint with position channels that this writer emits). Joint names are the text after
// ROOT/JOINT up to `{` or the end of the line (words joined by one space).
//
// Rejected, each with a ModelError "<file>: line <n>: <what> (rule: <rule>)": a missing
// HIERARCHY, ROOT or MOTION, a second ROOT (one skeleton per file), a joint without OFFSET or
// CHANNELS, an unknown channel, a channel listed twice in one joint, a CHANNELS count that
// disagrees with the names that follow, duplicate joint names, a motion line whose value count is
// not the sum of all CHANNELS, fewer motion lines than `Frames:` declares, more than one extra
// line after them, a value that is not a number, NaN or infinite, or beyond kMaxBvhMagnitude,
// control characters (binary data) in the hierarchy, and anything beyond the limits below.
// Tolerated with a warning: exactly one complete extra motion line after the declared frames
// (boxing_toes_zxy.bvh declares 3069 frames and holds 3070 lines); it is ignored, so the clip has
// the declared number of frames, as three.js and assimp read it.
//
// Memory: nothing is reserved from what the header claims. Frame storage is reserved only after
// the first motion line, for at most as many frames as the remaining bytes can hold at that
// line's length, so a 10⁹-frame header over a short file allocates nothing large.
//
// Import (load_bvh_file / load_bvh_string): the character becomes the BVH skeleton. The ROOT is a
// free joint; every other joint is spherical (whatever rotation channels it has, even none), or
// free when it has position channels. An End Site becomes a fixed link named "<joint>_end" (made
// unique with "_2", "_3", ... when the name is taken). Link frames sit at the joints with the
// rest orientation the identity (X_PJ = translation(OFFSET · scale)). Axes are kept: BVH is Y-up
// with characters facing +Z, as pindrag is. Masses: `total_mass` is split over the links in
// proportion to the length of the bones leaving each joint (to its child joints and End Sites,
// at least 2% of the height each), and each bone is a capsule (radius 12% of its length, clamped
// to [1%, 5%] of the height) that gives the inertia and is added as collision geometry.
//
// Units: BVH has none. `scale` is metres per file unit. By default it is chosen from the largest
// extent of the rest skeleton (all channels zero) among metres (1), centimetres (0.01),
// millimetres (0.001), inches (0.0254) and CMU units (1/0.45 inch = 0.056444 m, mocap.cs.cmu.edu
// FAQ): the candidate that makes that extent closest to 1.7 m (ratio on a log scale). With the
// shared files: CMU cgspeed files → CMU units, the metre PFNN file → metres, the Mixamo, OptiTrack
// and Biovision boxing files (≈ 175 units tall) → centimetres. A skeleton with no extent gets 1.
//
// Writing (write_bvh / save_bvh_file): one ROOT with OFFSET 0 0 0 and 6 channels (positions
// first), every other joint 3 rotation channels, or 6 when its translation moves (a free or
// prismatic joint; then OFFSET is 0 0 0 and the position channels carry the whole translation, so
// readers that add and readers that replace agree). Fixed links fold into their parent's offset;
// a fixed link with no moving joint below it becomes an End Site, and a leaf joint without one
// gets `End Site { OFFSET 0 0 0 }` (not when the layout of an imported file names it, so files
// without End Sites stay that way). Each written joint's rotation is its link frame relative to
// its written parent, so any Model works, whatever its rest placements. Tabs, `\n`, exact-case
// keywords, values in fixed notation with 6 decimals, no exponents, no "-0.000000"; `Frame Time`
// in its shortest exact decimal form with at least 7 significant digits. Euler angles are
// unwrapped across frames (the equivalent triple closest to the previous frame). Names are
// sanitized to [A-Za-z0-9_]+ (other bytes become '_') and made unique with "_2", "_3", ...
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"
#include "core/model_builder.hpp"
#include "io/core_names.hpp"

namespace io {

/// Largest BVH file read (bytes); larger files are refused before reading.
constexpr std::size_t kMaxBvhBytes = std::size_t{256} << 20;
/// Longest line accepted (bytes): kMaxBvhJoints joints × 6 values fit with room to spare.
constexpr std::size_t kMaxBvhLineBytes = std::size_t{1} << 20;
/// Most ROOT/JOINT entries, and most End Sites, in one file.
constexpr int kMaxBvhJoints = 4096;
/// Largest `Frames:` accepted (about 23 hours at 120 fps).
constexpr long kMaxBvhFrames = 10'000'000;
/// Largest magnitude of an OFFSET component or a motion value.
constexpr double kMaxBvhMagnitude = 1e9;
/// Largest `Frame Time:` accepted (seconds).
constexpr double kMaxBvhFrameTime = 3600.0;
/// Metres per CMU length unit: (1 / 0.45) inch (mocap.cs.cmu.edu FAQ).
constexpr double kCmuUnit = 2.54 / 45.0;

enum class BvhChannel : std::uint8_t {
  kXposition,
  kYposition,
  kZposition,
  kXrotation,
  kYrotation,
  kZrotation
};
/// "Xposition", ..., "Zrotation" (the exact case writers use).
const char* to_string(BvhChannel c);
inline bool is_rotation(BvhChannel c) { return c >= BvhChannel::kXrotation; }
/// 0, 1, 2 for X, Y, Z.
inline int channel_axis(BvhChannel c) { return static_cast<int>(c) % 3; }

/// Three distinct axes (0 = X, 1 = Y, 2 = Z) in file order: "ZXY" is {2, 0, 1}, R = Rz Rx Ry.
using BvhRotationOrder = std::array<int, 3>;
/// "ZXY", "zxy", ... → the order; empty for anything but a permutation of X, Y, Z.
std::optional<BvhRotationOrder> parse_rotation_order(std::string_view s);
std::string to_string(const BvhRotationOrder& order);
/// R = R_a0(angles[0]) R_a1(angles[1]) R_a2(angles[2]) (intrinsic, radians).
Matrix3 euler_to_matrix(const BvhRotationOrder& order, const Vector3& angles);
/// Angles (radians) with euler_to_matrix(order, angles) == R. Without `previous`: the middle angle
/// in [-π/2, π/2], the others in (-π, π]. With `previous`: of the two equivalent triples, each
/// shifted by multiples of 2π, the one closest to `previous` (Euler unwrapping). At the singular
/// middle angle ±π/2 the first angle is kept from `previous` (0 without).
Vector3 matrix_to_euler(const Matrix3& R, const BvhRotationOrder& order,
                        const Vector3* previous = nullptr);

/// One ROOT, JOINT or End Site of a BVH hierarchy.
struct BvhNode {
  enum class Kind : std::uint8_t { kRoot, kJoint, kEndSite };
  Kind kind = Kind::kJoint;
  std::string name;                  // empty for an End Site
  int parent = -1;                   // index in BvhDocument::nodes; -1 for the ROOT
  Vector3 offset = Vector3::Zero();  // file units, in the parent's frame
  std::vector<BvhChannel> channels;  // file order; empty for an End Site
  int first_value = 0;               // index of its first channel within a frame's values
  int line = 0;                      // line of its ROOT / JOINT / End keyword (0 when written)
  bool is_end_site() const { return kind == Kind::kEndSite; }
};

/// A BVH file as written: hierarchy, frame count and time, values in file units and degrees.
struct BvhDocument {
  std::vector<BvhNode> nodes;  // depth-first file order; nodes[0] is the ROOT
  int channels = 0;            // values per frame (sum of every joint's CHANNELS)
  int frames = 0;
  double frame_time = 1.0 / 30.0;
  std::vector<double> values;  // frames × channels, row-major
  std::vector<std::string> warnings;

  const double* frame(int f) const { return values.data() + static_cast<std::size_t>(f) * channels; }
  int joint_count() const;
};

/// Parses BVH text; `source_name` starts every message.
/// @throws ModelError "<source>: line <n>: <what> (rule: ...)"
BvhDocument parse_bvh(std::string_view text, const std::string& source_name);

/// BVH text of a document: tabs, `\n`, exact-case keywords, %.6f-style values (see above).
/// @throws std::invalid_argument when the document is inconsistent (value count, order of nodes)
///         or holds what parse_bvh would refuse (a value beyond kMaxBvhMagnitude, more frames or
///         joints than the limits), so that whatever is written reads back
std::string format_bvh(const BvhDocument& doc);

/// World pose of every node (file units, file order) for frame f, or for the rest pose (every
/// channel zero, i.e. OFFSETs only) when f < 0. An End Site has its joint's rotation.
std::vector<Transform> bvh_world_poses(const BvhDocument& doc, int frame);
/// Rotation of one joint from its channel values (R = product in file order).
Matrix3 bvh_joint_rotation(const BvhNode& node, const double* frame_values);

/// Vertical (Y) and largest extent of the rest skeleton over all nodes (file units).
struct BvhExtent {
  double height = 0;
  double largest = 0;
};
BvhExtent bvh_rest_extent(const BvhDocument& doc);

/// The automatic scale (metres per file unit) and the unit it stands for ("centimetres", ...).
struct BvhUnit {
  double scale = 1.0;
  std::string unit;
};
BvhUnit bvh_auto_scale(const BvhDocument& doc);

/// What the writer needs to write an imported skeleton back the same way.
struct BvhLayout {
  struct Joint {
    std::string name;                  // as in the file; also the model's link name
    std::vector<BvhChannel> channels;  // as in the file
  };
  std::vector<Joint> joints;  // file order
  double scale = 1.0;         // metres per file unit applied at import
  /// The joint with this (file) name, or nullptr.
  const Joint* find(std::string_view name) const;
};

struct BvhImportOptions {
  std::optional<double> scale;  // metres per file unit; empty: bvh_auto_scale
  double total_mass = 70.0;     // kg, split over the links by bone length
  std::function<void(double)> progress;  // fraction done in [0, 1], called a few dozen times
};

struct BvhImport {
  std::shared_ptr<const Model> model;
  Clip clip;
  BvhLayout layout;
  std::string unit;         // "centimetres", ..., or "option" when BvhImportOptions::scale is set
  double height = 0;        // rest height, metres
  std::vector<int> node_link;  // model link of every BVH node in file order (End Sites too)
  std::vector<std::string> warnings;
};

/// Imports a parsed document. `source_name` starts every message.
/// @throws ModelError naming the source and the rule broken
BvhImport import_bvh(const BvhDocument& doc, const std::string& source_name,
                     const BvhImportOptions& options = {});
/// Parses and imports BVH text.
BvhImport load_bvh_string(std::string_view text, const std::string& source_name,
                          const BvhImportOptions& options = {});
/// Reads (at most kMaxBvhBytes), parses and imports a BVH file; the model is named after it.
BvhImport load_bvh_file(const std::string& path, const BvhImportOptions& options = {});

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
BvhDocument make_bvh_document(const Model& model, const Clip& clip,
                              const BvhExportOptions& options = {});
/// format_bvh(make_bvh_document(...)).
std::string write_bvh(const Model& model, const Clip& clip, const BvhExportOptions& options = {});
/// Writes write_bvh(...) to `path` atomically: a temporary file in the same folder, fsync, rename
/// over `path`, fsync of the folder.
/// @throws std::invalid_argument (see above) or std::system_error naming the path
void save_bvh_file(const Model& model, const Clip& clip, const std::string& path,
                   const BvhExportOptions& options = {});

/// `name` with every byte outside [A-Za-z0-9_] replaced by '_' ("joint" when empty).
std::string sanitize_bvh_name(std::string_view name);

}  // namespace io
