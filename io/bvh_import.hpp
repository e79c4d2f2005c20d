// BVH import: a parsed document (io/bvh_parser.hpp) becomes a Model and a Clip.
//
// The character becomes the BVH skeleton. The ROOT is a free joint; every other joint is
// spherical (whatever rotation channels it has, even none), or free when it has position
// channels whose translation moves. A non-root joint whose translation (its OFFSET with the
// position channels' values in place, io/bvh_document.hpp) stays within
// kBvhConstantTranslationTolerance of the figure's size of one constant over every frame is
// spherical too, with that constant (the midrange of each component) as its joint origin: exports
// from MotionBuilder or Blender give every joint 6 channels whose positions only repeat the
// OFFSET, and free joints there would let bones stretch when edited. The world poses stay those of
// the file to within the deviation allowed (exactly, up to rounding, for constant values). A
// document without frames keeps such joints free. An End Site becomes a fixed link named
// "<joint>_end" (made unique with "_2", "_3", ... when the name is taken). Link frames sit at the
// joints with the rest orientation the identity (X_PJ = translation(OFFSET · scale)). Axes are
// kept: BVH is Y-up with characters facing +Z, as pindrag is.
//
// Masses: `total_mass` is split over the links in proportion to the length of the bones leaving
// each joint (to the OFFSETs of its child joints and End Sites, at least 2% of the figure's size
// each), and each bone is a capsule (radius 12% of its length, clamped to [1%, 5%] of the
// figure's size, along the shortest arc from +Z to the bone) that gives the inertia and is added
// as collision geometry.
// Bones no longer than 1e-9 of the figure's size get no capsule; a joint without a longer one (a
// leaf, for one) gets a sphere of radius 2% of the figure's size instead. The figure's size is the
// largest extent of the rest skeleton in metres, or 1 m when that is under 1 µm (no extent). So
// any document the reader accepts imports, from offsets of 1e9 units down to denormals.
//
// Units: BVH has none. `scale` is metres per file unit. By default it is chosen from the largest
// extent of the rest skeleton (all channels zero) among metres (1), centimetres (0.01),
// millimetres (0.001), inches (0.0254) and CMU units (1/0.45 inch = 0.056444 m, mocap.cs.cmu.edu
// FAQ): the candidate that makes that extent closest to 1.7 m (ratio on a log scale). With the
// shared files: CMU cgspeed files → CMU units, the metre PFNN file → metres, the Mixamo, OptiTrack
// and Biovision boxing files (≈ 175 units tall) → centimetres. A skeleton with no extent gets 1.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "io/bvh_document.hpp"
#include "io/clip_budget.hpp"

namespace io {

/// Metres per CMU length unit: (1 / 0.45) inch (mocap.cs.cmu.edu FAQ).
constexpr double kCmuUnit = 2.54 / 45.0;

/// The automatic scale (metres per file unit) and the unit it stands for ("centimetres", ...).
struct BvhUnit {
  double scale = 1.0;
  std::string unit;
};
BvhUnit bvh_auto_scale(const BvhDocument& doc);

/// A unit chosen by name for a BVH import: "auto" (empty: bvh_auto_scale), "m", "cm", "mm",
/// "in" or "cmu"; the scale in metres per file unit.
/// @throws std::invalid_argument naming `field` and the allowed names
std::optional<double> parse_bvh_import_unit(std::string_view name, std::string_view field);
/// The name of a scale among the units above ("centimetres", ...), else "<scale> m per unit".
std::string bvh_unit_name(double scale);

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

/// Largest deviation of a non-root joint's translation from one constant over all frames, as a
/// fraction of the figure's size (the largest rest extent in metres, 1 m without one), under which
/// its position channels count as constant (noise) and the joint imports as rotational: 1e-4, i.e.
/// 0.17 mm on a 1.7 m figure. Float noise of exporters (float32: ~1e-7 of the figure, written
/// with 6 decimals) is far below it; no visible or mocap-measurable motion (markers resolve
/// ~0.1-1 mm) is; relative to the figure, so the choice does not depend on the unit.
constexpr double kBvhConstantTranslationTolerance = 1e-4;

struct BvhImportOptions {
  std::optional<double> scale;           // metres per file unit; empty: bvh_auto_scale
  double total_mass = 70.0;              // kg, split over the links by bone length
  std::function<void(double)> progress;  // fraction done in [0, 1], called a few dozen times
  ClipBudget budget;  // load_bvh_string and load_bvh_file refuse a longer clip (parse_bvh)
  /// A clip loaded onto an existing character: a joint with position channels that this model
  /// has (by link name) takes its joint type from it instead of from the frames: free stays free;
  /// rotational is rotational, and a translation that moves more than the tolerance is then an
  /// error naming the joint (the character cannot play it). Joints it lacks decide as usual.
  const Model* joint_types_of = nullptr;
};

struct BvhImport {
  std::shared_ptr<const Model> model;
  Clip clip;
  BvhLayout layout;
  std::string unit;   // "centimetres", ..., or "option" when BvhImportOptions::scale is set
  double height = 0;  // rest height, metres
  std::vector<int> node_link;  // model link of every BVH node in file order (End Sites too)
  /// Non-root joints with position channels (file order): constant translation, imported as
  /// rotational joints at that offset, and truly translating ones, imported free.
  std::vector<std::string> constant_translation_joints;
  std::vector<std::string> translating_joints;
  std::vector<std::string> warnings;
};

/// The non-root joints of `layout` that have position channels, split by the joint `model` gives
/// them: `constant` (imported rotational at a constant offset) and `translating` (free); file
/// order. For a model and layout from import_bvh, the lists BvhImport holds.
struct BvhTranslationJoints {
  std::vector<std::string> constant;
  std::vector<std::string> translating;
};
BvhTranslationJoints bvh_translation_joints(const Model& model, const BvhLayout& layout);

/// Imports a parsed document. `source_name` starts every message.
/// @throws ModelError naming the source and the rule broken
BvhImport import_bvh(const BvhDocument& doc,
                     const std::string& source_name,
                     const BvhImportOptions& options = {});
/// Parses and imports BVH text.
BvhImport load_bvh_string(std::string_view text,
                          const std::string& source_name,
                          const BvhImportOptions& options = {});
/// Reads (at most kMaxBvhBytes, io/read_file.hpp), parses and imports a BVH file; the model is
/// named after it.
/// @throws ModelError, also for a file that cannot be read (the message of io::read_file)
BvhImport load_bvh_file(const std::string& path, const BvhImportOptions& options = {});

}  // namespace io
