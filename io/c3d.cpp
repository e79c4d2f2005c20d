// The C3D reader (io/c3d.hpp): the header, the trial's layout resolved from the header and the
// parameters, and the samples.
#include "io/c3d.hpp"

#include <cmath>
#include <limits>
#include <optional>

#include "io/c3d_format.hpp"
#include "io/read_file.hpp"

namespace io {

namespace {

using namespace c3d_detail;

// byte 2 of every C3D file
constexpr int kHeaderKey = 0x50;
// the largest frame count the 16-bit forms hold; beyond it the 32-bit forms count
constexpr std::int64_t kMax16BitFrames = 65535;

// The header block (C3D User Guide, "The Header Section"), 16-bit words numbered from 1.
struct Header {
  std::size_t parameter_block = 0;  // word 1, first byte
  int points = 0;                   // word 2
  int analog_per_frame = 0;         // word 3: analog values stored after each frame's points
  int first_frame = 0;              // word 4
  int last_frame = 0;               // word 5
  double scale = 0;                 // words 7-8, a float
  std::size_t data_start = 0;       // word 9: first block of the data section
  double rate = 0;                  // words 11-12, a float
};

// The checks that need nothing but the first block: its size, its key and where the parameters
// are, so that their processor type (which decides how the header's floats read) can be found.
Header open_header(std::string_view bytes, const std::string& source) {
  if (bytes.size() < kBlockBytes) {
    fail(source, "header: the file is " + std::to_string(bytes.size()) +
                     " bytes (rule: a C3D file starts with a 512-byte header block)");
  }
  const int key = static_cast<std::uint8_t>(bytes[1]);
  if (key != kHeaderKey) {
    fail(source, "header: byte 2 is " + std::to_string(key) +
                     " (rule: it is 80, 0x50, in every C3D file; not a C3D file?)");
  }
  Header h;
  h.parameter_block = static_cast<std::uint8_t>(bytes[0]);
  if (h.parameter_block < 2) {
    fail(source, "header: parameter block " + std::to_string(h.parameter_block) +
                     " (rule: the parameters start at block 2 or later; block 1 is the header)");
  }
  if ((h.parameter_block - 1) * kBlockBytes + 4 > bytes.size()) {
    fail(source, "header: parameter block " + std::to_string(h.parameter_block) +
                     " is beyond the file (" + std::to_string(blocks_in(bytes.size())) +
                     " blocks)");
  }
  return h;
}

// Resolves the data section's layout from the header and the parameters, checking each field
// against the others and the file size, then reads the samples.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& source)
      : bytes_(bytes),
        source_(source),
        header_(open_header(bytes, source)),
        params_(bytes, header_.parameter_block, source) {
    const Processor cpu = params_.processor();
    header_.points = u16(bytes, 2);
    header_.analog_per_frame = u16(bytes, 4);
    header_.first_frame = u16(bytes, 6);
    header_.last_frame = u16(bytes, 8);
    header_.scale = real(bytes, 12, cpu);
    header_.data_start = u16(bytes, 16);
    header_.rate = real(bytes, 20, cpu);
  }

  C3dTrial read(const ClipBudget& budget) {
    C3dTrial t;
    points_ = points();
    t.rate_hz = rate_ = rate();
    scale_ = scale();
    frames(t);
    analog();
    data_start();
    t.labels = labels();
    units(t);
    const std::string refusal = clip_budget_refusal(budget, t.frames, 1 / rate_, 3 * points_);
    if (!refusal.empty()) fail(refusal);
    check_data_size(t.frames);
    samples(t);
    strip_subject(t);
    return t;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { c3d_detail::fail(source_, what); }

  std::string points_field() const {
    return params_.find("POINT", "USED") ? "POINT:USED" : "the header's point count";
  }

  int points() const {
    const auto used = params_.count("POINT", "USED");
    if (used && *used != header_.points) {
      fail("POINT:USED is " + std::to_string(*used) + " but the header's point count is " +
           std::to_string(header_.points) + " (rule: they agree)");
    }
    return header_.points;
  }

  double rate() const {
    const auto param = params_.number("POINT", "RATE");  // refuses NaN and infinity
    const double r = param.value_or(header_.rate);
    const std::string field = param ? "POINT:RATE" : "header: frame rate";
    if (std::isnan(r)) fail(field + " is NaN (rule: the frame rate is a finite number)");
    if (!(r > 0)) {
      fail(field + " is " + number_text(r) + " (rule: the frame rate must be positive)");
    }
    if (r > kMaxC3dRateHz) {
      fail(field + " is " + number_text(r) +
           " Hz (rule: at most kMaxC3dRateHz = " + number_text(kMaxC3dRateHz) + " Hz)");
    }
    return r;
  }

  // > 0: int16 data times the scale; < 0: float data, |scale| applies to the residual only
  double scale() const {
    const auto param = params_.number("POINT", "SCALE");  // refuses NaN and infinity
    if (!param && !std::isfinite(header_.scale)) {
      fail("header: scale factor is " +
           std::string(std::isnan(header_.scale) ? "NaN" : "infinite") +
           " (rule: a finite number)");
    }
    const double s = param.value_or(header_.scale);
    if (s == 0) {
      fail(std::string(param ? "POINT:SCALE" : "header: scale factor") +
           " is 0 (rule: non-zero; > 0 means integer data, < 0 float data)");
    }
    if (param && std::isfinite(header_.scale) && header_.scale != 0 &&
        (s < 0) != (header_.scale < 0)) {
      fail("POINT:SCALE " + number_text(s) + " and the header's scale factor " +
           number_text(header_.scale) +
           " differ in sign (rule: they agree; the sign picks integer or float data)");
    }
    return s;
  }

  // POINT:FRAMES (16-bit, or the float the User Guide allows); beyond 65535 frames
  // POINT:LONG_FRAMES or TRIAL:ACTUAL_START_FIELD/ACTUAL_END_FIELD; the header's frame range
  // when POINT:FRAMES is absent
  void frames(C3dTrial& t) const {
    std::int64_t frames = 0;
    std::int64_t first = header_.first_frame;
    std::string field = "POINT:FRAMES";
    const Parameter* point_frames = params_.find("POINT", "FRAMES");
    if (point_frames) {
      frames = *params_.count("POINT", "FRAMES");
    } else {
      field = "the header's frame range";
      if (header_.last_frame + 1 < header_.first_frame) {
        fail("header: last frame " + std::to_string(header_.last_frame) +
             " is before first frame " + std::to_string(header_.first_frame) +
             " (rule: last >= first - 1)");
      }
      frames = header_.last_frame - header_.first_frame + 1;
    }
    if (!point_frames || point_frames->type != 4) {
      const auto long_frames = params_.count("POINT", "LONG_FRAMES");
      const auto start = params_.long_count("TRIAL", "ACTUAL_START_FIELD");
      const auto end = params_.long_count("TRIAL", "ACTUAL_END_FIELD");
      if (long_frames && *long_frames > kMax16BitFrames) {
        frames = *long_frames;
        field = "POINT:LONG_FRAMES";
      } else if (start && end && *end >= *start && *end - *start + 1 > kMax16BitFrames) {
        frames = *end - *start + 1;
        first = *start;
        field = "TRIAL:ACTUAL_START_FIELD/ACTUAL_END_FIELD";
      }
    }
    if (frames > kMaxC3dFrames) {
      fail(field + " gives " + std::to_string(frames) +
           " frames (rule: at most kMaxC3dFrames = " + std::to_string(kMaxC3dFrames) + ")");
    }
    if (first > std::numeric_limits<int>::max()) {
      fail("TRIAL:ACTUAL_START_FIELD is " + std::to_string(first) + " (rule: at most " +
           std::to_string(std::numeric_limits<int>::max()) + ")");
    }
    t.frames = static_cast<int>(frames);
    t.first_frame = static_cast<int>(first);
  }

  // the header's analog values per frame, checked against ANALOG:USED × ANALOG:RATE / POINT:RATE
  // when the rates' ratio is whole
  void analog() {
    analog_ = header_.analog_per_frame;
    const auto used = params_.count("ANALOG", "USED");
    if (!used || *used == 0) return;
    const auto analog_rate = params_.number("ANALOG", "RATE");
    if (!analog_rate || !(*analog_rate > 0)) return;
    const double ratio = *analog_rate / rate_;
    const double whole = std::round(ratio);
    if (whole < 1 || std::abs(ratio - whole) > 1e-6 * whole) return;
    const double expected = static_cast<double>(*used) * whole;
    if (expected != analog_) {
      fail("header: " + std::to_string(analog_) + " analog values per frame, but ANALOG:USED " +
           std::to_string(*used) + " x ANALOG:RATE " + number_text(*analog_rate) +
           " / POINT:RATE " + number_text(rate_) + " = " + number_text(expected) +
           " (rule: they agree)");
    }
  }

  void data_start() {
    const std::size_t block = header_.data_start;
    const auto param = params_.count("POINT", "DATA_START");
    if (param && static_cast<std::size_t>(*param) != block) {
      fail("POINT:DATA_START is " + std::to_string(*param) +
           " but the header's data start block is " + std::to_string(block) +
           " (rule: they agree)");
    }
    const std::size_t after_params = params_.first_block() + params_.block_count();
    if (block < after_params) {
      fail("header: data start block " + std::to_string(block) +
           " is not after the parameter section (blocks " + std::to_string(params_.first_block()) +
           " to " + std::to_string(after_params - 1) + "; rule: the data follows the parameters)");
    }
    if ((block - 1) * kBlockBytes > bytes_.size()) {
      fail("header: data start block " + std::to_string(block) + " is beyond the file (" +
           std::to_string(blocks_in(bytes_.size())) + " blocks)");
    }
    data_offset_ = (block - 1) * kBlockBytes;
  }

  // POINT:LABELS, then LABELS2, LABELS3, ... until every point has one
  std::vector<std::string> labels() const {
    std::vector<std::string> all;
    if (points_ == 0) return all;
    const auto first = params_.strings("POINT", "LABELS");
    if (!first) {
      fail("POINT:LABELS is missing but " + points_field() + " is " + std::to_string(points_) +
           " (rule: every point has a label)");
    }
    all = *first;
    std::string names = "POINT:LABELS";
    for (int k = 2; static_cast<int>(all.size()) < points_; ++k) {
      const auto more = params_.strings("POINT", "LABELS" + std::to_string(k));
      if (!more) break;
      names += (k == 2 ? " with LABELS" : ", LABELS") + std::to_string(k);
      all.insert(all.end(), more->begin(), more->end());
    }
    if (static_cast<int>(all.size()) < points_) {
      fail(names + " has " + std::to_string(all.size()) + " labels but " + points_field() + " is " +
           std::to_string(points_) +
           " (rule: one label per point; LABELS2, LABELS3... continue the list)");
    }
    all.resize(static_cast<std::size_t>(points_));
    return all;
  }

  void units(C3dTrial& t) const {
    const auto units = params_.strings("POINT", "UNITS");
    t.units = units && !units->empty() ? units->front() : "";
    if (t.units.empty()) {
      t.units = "mm";
      t.warnings.push_back(source_ + ": POINT:UNITS is absent or blank; millimetres assumed");
    }
    const struct {
      const char* name;
      double metres;
    } kUnits[] = {{"mm", 1e-3}, {"cm", 1e-2}, {"m", 1.0}};
    for (const auto& u : kUnits) {
      if (t.units == u.name) {
        t.to_metres = u.metres;
        return;
      }
    }
    fail("POINT:UNITS is " + shown_text(t.units) + " (rule: mm, cm or m)");
  }

  std::size_t word_bytes() const { return scale_ < 0 ? 4 : 2; }
  // bytes per frame: 4 words per point (x, y, z, residual), then the analog values
  std::size_t frame_bytes() const {
    return (4 * static_cast<std::size_t>(points_) + static_cast<std::size_t>(analog_)) *
           word_bytes();
  }

  void check_data_size(int frames) const {
    // frames ≤ kMaxC3dFrames and a frame ≤ 327675 words: no overflow in 64 bits
    const std::uint64_t need = static_cast<std::uint64_t>(frames) * frame_bytes();
    const std::uint64_t have = bytes_.size() - data_offset_;
    if (need > have) {
      fail("data: " + std::to_string(frames) + " frames of " + std::to_string(points_) +
           " points and " + std::to_string(analog_) + " analog values in " +
           std::to_string(word_bytes()) + "-byte words need " + std::to_string(need) +
           " bytes from block " + std::to_string(header_.data_start) + ", but the file holds " +
           std::to_string(have) + " there (rule: the data section holds every frame; truncated " +
           "file?)");
    }
  }

  // x, y, z and the residual word of each point, frame by frame; analog values are skipped
  void samples(C3dTrial& t) const {
    const std::size_t n = static_cast<std::size_t>(t.frames) * static_cast<std::size_t>(points_);
    t.positions.assign(n, Eigen::Vector3d::Zero());
    t.present.assign(n, 0);
    const bool floats = scale_ < 0;
    const std::size_t word = word_bytes();
    for (int f = 0; f < t.frames; ++f) {
      const std::size_t frame_at = data_offset_ + static_cast<std::size_t>(f) * frame_bytes();
      for (int p = 0; p < points_; ++p) {
        const std::size_t at = frame_at + 4 * word * static_cast<std::size_t>(p);
        const auto value = [&](int k) {
          const std::size_t w = at + k * word;
          return floats ? real(bytes_, w, params_.processor()) : i16(bytes_, w) * scale_;
        };
        const double residual = floats ? value(3) : i16(bytes_, at + 6);
        if (!std::isfinite(residual)) {
          fail(where(t, f, p) + ": the residual word is " +
               (std::isnan(residual) ? "NaN" : "infinite") + " (rule: a finite number)");
        }
        // a negative residual marks a missing sample; writers also fill gaps with zeros
        const Eigen::Vector3d x(value(0), value(1), value(2));
        if (residual < 0 || (x.x() == 0 && x.y() == 0 && x.z() == 0)) continue;
        for (int k = 0; k < 3; ++k) {
          if (!std::isfinite(x[k])) {
            fail(where(t, f, p) + ": " + std::string(1, "XYZ"[k]) + " is " +
                 (std::isnan(x[k]) ? "NaN" : "infinite") + " (rule: a present sample is finite)");
          }
        }
        const std::size_t i = static_cast<std::size_t>(f) * points_ + p;
        t.positions[i] = x * t.to_metres;
        t.present[i] = 1;
      }
    }
  }

  std::string where(const C3dTrial& t, int frame, int point) const {
    return "data: frame " + std::to_string(frame) + " (file frame " +
           std::to_string(static_cast<std::int64_t>(t.first_frame) + frame) + "), point " +
           std::to_string(point) + " " + shown_text(t.labels[point]);
  }

  // `Male:LFHD`, `Male:RFHD`, ...: a prefix every label shares becomes the subject
  static void strip_subject(C3dTrial& t) {
    if (t.labels.empty()) return;
    const std::size_t colon = t.labels[0].find(':');
    if (colon == std::string::npos || colon == 0) return;
    const std::string prefix = t.labels[0].substr(0, colon + 1);
    for (const std::string& l : t.labels) {
      if (l.size() <= prefix.size() || l.compare(0, prefix.size(), prefix) != 0) return;
    }
    t.subject = prefix.substr(0, colon);
    for (std::string& l : t.labels) l.erase(0, prefix.size());
  }

  std::string_view bytes_;
  const std::string& source_;
  Header header_;
  Parameters params_;
  int points_ = 0;
  int analog_ = 0;
  double rate_ = 0;
  double scale_ = 0;
  std::size_t data_offset_ = 0;
};

}  // namespace

C3dTrial parse_c3d(std::string_view bytes,
                   const std::string& source_name,
                   const ClipBudget& budget) {
  return Reader(bytes, source_name).read(budget);
}

C3dTrial read_c3d(const std::string& path, const ClipBudget& budget) {
  return parse_c3d(read_file(path, kMaxC3dBytes, "a C3D file"), path, budget);
}

}  // namespace io
