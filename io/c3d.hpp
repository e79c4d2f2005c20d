// The C3D reader: marker trajectories from a motion-capture trial (c3d.org, the C3D User Guide).
//
// Read: the 512-byte header block, the parameter section (groups and parameters, locked or not,
// chained by their next-record offsets) and the 3D point data of Intel (processor 84) and DEC
// (85, VAX floats) files, integer (POINT:SCALE > 0: int16 × scale) or float (POINT:SCALE < 0:
// float32). Labels come from POINT:LABELS, LABELS2, LABELS3… (concatenated), trimmed of trailing
// blanks; a prefix shared by every label (`Male:LFHD`) becomes the subject. The frame count is
// POINT:FRAMES (an unsigned 16-bit integer, or a float), or, beyond 65535 frames, POINT:LONG_FRAMES
// or TRIAL:ACTUAL_START_FIELD/ACTUAL_END_FIELD (32-bit values as two 16-bit words). Analog samples
// stored after each frame's points are skipped. Positions are converted to metres from
// POINT:UNITS (mm, cm or m; mm with a warning when absent).
//
// Kept as in the file: the lab axes (C3D labs are usually Z up; POINT:X_SCREEN/Y_SCREEN say how
// the file's authors viewed them); converting to pindrag's Y-up world is the caller's step.
//
// Refused, each with a C3dError "<source>: <field>: <what> (rule: <rule>)": a file shorter than
// its header, a second byte that is not 0x50, big-endian MIPS files (processor 86) and unknown
// processors, a parameter chain that leaves its section or runs backwards, a parameter type
// other than -1, 1, 2, 4 or more than 7 dimensions, a header and parameter that disagree (point
// count, data start, the sign of the scale), a NaN or zero scale, a frame rate that is not
// positive and finite, fewer labels than points, unknown units, a data start inside the
// parameters or beyond the file, a data section shorter than frames × (4 × points + analog) words,
// and a present sample that is not finite. Every count and offset is checked against the file
// size before it is used, so memory follows the file: a bogus frame count allocates nothing.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "io/clip_budget.hpp"

namespace io {

/// Largest C3D file read_c3d reads (bytes); larger files are refused before reading.
constexpr std::size_t kMaxC3dBytes = std::size_t{512} << 20;
/// Most frames in one trial (about 28 hours at 1000 Hz).
constexpr std::int64_t kMaxC3dFrames = 100'000'000;
/// Highest point rate accepted (Hz).
constexpr double kMaxC3dRateHz = 1e6;

/// A C3D file that cannot be read. what() starts with the source name and names the field.
class C3dError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The marker trajectories of one trial. Samples are frame-major: sample (f, p) is at
/// index f × point_count() + p of `positions` and `present`.
struct C3dTrial {
  std::string subject;              // the prefix every label shared (`Male` of `Male:LFHD`), or ""
  std::vector<std::string> labels;  // one per point, without the subject prefix
  double rate_hz = 0;               // frames per second (POINT:RATE)
  std::string units;                // POINT:UNITS as in the file: "mm", "cm" or "m"
  double to_metres = 1;             // metres per file unit
  int first_frame = 1;              // the file's number for frame 0
  int frames = 0;                   // number of frames (also when there are no points)
  std::vector<Eigen::Vector3d> positions;  // metres, lab axes; zero where missing (frames × points)
  std::vector<std::uint8_t> present;       // 1 measured, 0 missing: residual < 0 or x = y = z = 0
  std::vector<std::string> warnings;       // what was assumed (units absent)

  int frame_count() const { return frames; }
  int point_count() const { return static_cast<int>(labels.size()); }
  /// Seconds from frame 0 to `frame`.
  double time(int frame) const { return frame / rate_hz; }
  /// @throws std::out_of_range outside [0, frame_count()) × [0, point_count())
  const Eigen::Vector3d& position(int frame, int point) const;
  /// @throws std::out_of_range outside [0, frame_count()) × [0, point_count())
  bool is_present(int frame, int point) const;
  /// Index of the point labelled `label` (with or without the subject prefix), or -1.
  int find(std::string_view label) const;
  /// Missing samples over all samples (0 for an empty trial).
  double missing_fraction() const;
};

/// Reads a C3D file held in memory; `source_name` starts every message. A trial of more frames
/// or values (frames × points × 3) than `budget` allows is refused before any sample is stored.
/// @throws C3dError "<source>: <field>: <what> (rule: <rule>)"
C3dTrial parse_c3d(std::string_view bytes,
                   const std::string& source_name,
                   const ClipBudget& budget = {});

/// Reads the C3D file at `path` (at most kMaxC3dBytes).
/// @throws FileError (io/read_file.hpp) when the file cannot be read or is too large, C3dError
///         as parse_c3d
C3dTrial read_c3d(const std::string& path, const ClipBudget& budget = {});

}  // namespace io
