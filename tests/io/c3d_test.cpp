// Tests for io/c3d.hpp: the two shared C3D files (counts, labels, units, gaps, and samples read a
// second way, straight from the bytes); synthetic files from a small writer below (integer and
// float data, DEC VAX floats checked against hand-encoded bytes, frame counts beyond 65535,
// LABELS2, analog values between frames, subject prefixes, units); malformed files, each refused
// with its field and rule named; and the fuzzing seeds in tests/fixtures/c3d, which are this
// writer's output.
#include "io/c3d.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>

#include "io/read_file.hpp"
#include "tests/fixtures/fixtures.hpp"

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string c3d_data_dir() { return fixtures::data_dir() + "/c3d"; }
std::string seeds_dir() { return fixtures::source_dir() + "/tests/fixtures/c3d"; }

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string le16(int v) {
  const auto u = static_cast<std::uint16_t>(v);
  return {static_cast<char>(u & 0xff), static_cast<char>(u >> 8)};
}

std::string ieee_bytes(double v) {
  const auto f = static_cast<float>(v);
  std::uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return le16(static_cast<int>(bits & 0xffff)) + le16(static_cast<int>(bits >> 16));
}

// VAX F_floating built from frexp (not from IEEE bits, as the reader does): v = m × 2^e with
// m in [0.5, 1) is 0.1f × 2^(E − 128), so E = e + 128 and f is m's 23 bits after the leading 1
std::string vax_bytes(double v) {
  if (v == 0) return std::string(4, '\0');
  int e = 0;
  const double m = std::frexp(std::abs(v), &e);
  std::int64_t significand = std::llround(std::ldexp(m, 24));
  if (significand == (std::int64_t{1} << 24)) {
    significand >>= 1;
    ++e;
  }
  const auto fraction = static_cast<std::uint32_t>(significand) & 0x7fffffu;
  const int first = (v < 0 ? 0x8000 : 0) | ((e + 128) << 7) | static_cast<int>(fraction >> 16);
  return le16(first) + le16(static_cast<int>(fraction & 0xffff));
}

struct Sample {
  double x = 0, y = 0, z = 0;
  double residual = 0;  // < 0: missing
};

// One group or parameter record. Numbers are encoded for the writer's processor when written;
// `raw` (text, or hand-made bytes) is written as it is.
struct Record {
  int id = 0;  // < 0: a group; > 0: a parameter of group −id
  std::string name;
  int type = 2;
  std::vector<int> dims;
  std::vector<double> numbers;
  std::string raw;
  bool locked = false;
};

// A small C3D writer: header block, parameter section, data section (C3D User Guide layout).
class C3dWriter {
 public:
  int processor = 84;
  std::size_t parameter_block = 2;
  int points = 0;
  int analog_per_frame = 0;  // header word 3
  int first_frame = 1;
  int last_frame = 0;
  double scale = -0.1;  // < 0: float data
  double rate = 100;
  int data_start = 0;             // 0: the block after the parameters
  bool last_offset_zero = false;  // end the chain with offset 0 instead of a zero name length
  std::vector<std::vector<Sample>> frames;
  double analog_value = 1234;  // every analog value written
  std::vector<Record> records;
  std::map<std::string, std::size_t> record_at;  // "GROUP:NAME" → byte of the record, by bytes()

  Record& group(int id, const std::string& name) {
    records.push_back({-id, name, 0, {}, {}, "", false});
    return records.back();
  }
  Record& numbers(int group, const std::string& name, int type, std::vector<double> v) {
    const std::vector<int> dims =
        v.size() == 1 ? std::vector<int>{} : std::vector<int>{static_cast<int>(v.size())};
    records.push_back({group, name, type, dims, std::move(v), "", false});
    return records.back();
  }
  Record& text(int group, const std::string& name, const std::vector<std::string>& items, int len) {
    std::string raw;
    for (const std::string& s : items) raw += s + std::string(len - s.size(), ' ');
    records.push_back({group, name, -1, {len, static_cast<int>(items.size())}, {}, raw, false});
    return records.back();
  }
  Record* find(const std::string& name) {
    for (Record& r : records) {
      if (r.name == name) return &r;
    }
    return nullptr;
  }
  void erase(const std::string& name) {
    std::erase_if(records, [&](const Record& r) { return r.name == name; });
  }

  std::string real(double v) const { return processor == 85 ? vax_bytes(v) : ieee_bytes(v); }

  std::string bytes() {
    // the section's size does not depend on DATA_START's value, so lay it out first
    const std::size_t section = 4 + serialize(false).size();
    const std::size_t blocks = std::max<std::size_t>(1, (section + 511) / 512);
    const int start = data_start ? data_start : static_cast<int>(parameter_block + blocks);
    if (Record* r = find("DATA_START")) r->numbers = {static_cast<double>(start)};
    std::string file(512, '\0');
    file[0] = static_cast<char>(parameter_block);
    file[1] = 0x50;
    file.replace(2, 2, le16(points));
    file.replace(4, 2, le16(analog_per_frame));
    file.replace(6, 2, le16(first_frame));
    file.replace(8, 2, le16(last_frame));
    file.replace(12, 4, real(scale));
    file.replace(16, 2, le16(start));
    file.replace(18, 2, le16(1));
    file.replace(20, 4, real(rate));
    file.resize((parameter_block - 1) * 512, '\0');
    const std::size_t section_at = file.size();
    file += std::string{1, 0x50, static_cast<char>(blocks), static_cast<char>(processor)};
    file += serialize(true, section_at + 4);
    file.resize(std::max(file.size(), static_cast<std::size_t>(start - 1) * 512), '\0');
    return file + data();
  }

 private:
  std::string encode(const Record& r) const {
    if (!r.raw.empty() || r.type == -1) return r.raw;
    std::string out;
    for (double v : r.numbers) {
      if (r.type == 1) out += static_cast<char>(static_cast<int>(v));
      if (r.type == 2) out += le16(static_cast<int>(v));
      if (r.type == 4) out += real(v);
    }
    return out;
  }

  std::string serialize(bool remember, std::size_t at = 0) {
    std::map<int, std::string> groups;
    for (const Record& r : records) {
      if (r.id < 0) groups[-r.id] = r.name;
    }
    std::string out;
    for (std::size_t i = 0; i < records.size(); ++i) {
      const Record& r = records[i];
      std::string body;
      if (r.id > 0) {
        body += static_cast<char>(r.type);
        body += static_cast<char>(r.dims.size());
        for (int d : r.dims) body += static_cast<char>(d);
        body += encode(r);
      }
      body += '\0';  // no description
      if (remember) record_at[(r.id > 0 ? groups[r.id] + ":" : "") + r.name] = at + out.size();
      const int length = static_cast<int>(r.name.size());
      out += static_cast<char>(r.locked ? -length : length);
      out += static_cast<char>(r.id);
      out += r.name;
      const bool last = i + 1 == records.size();
      out += le16(last && last_offset_zero ? 0 : static_cast<int>(2 + body.size()));
      out += body;
    }
    return out + std::string(2, '\0');  // a zero name length ends the chain
  }

  std::string data() const {
    std::string out;
    for (const auto& frame : frames) {
      for (const Sample& s : frame) {
        if (scale < 0) {
          out += real(s.x) + real(s.y) + real(s.z) + real(s.residual);
        } else {
          for (double v : {s.x, s.y, s.z}) out += le16(static_cast<int>(std::lround(v / scale)));
          out += le16(static_cast<int>(s.residual));
        }
      }
      for (int a = 0; a < analog_per_frame; ++a) {
        out += scale < 0 ? real(analog_value) : le16(static_cast<int>(analog_value));
      }
    }
    return out;
  }
};

constexpr int kPoint = 1;
constexpr int kAnalog = 2;
constexpr int kTrial = 3;

// A trial: `points` markers moving along lines, marker 1 missing on odd frames; the POINT group
// (USED, FRAMES, DATA_START, SCALE, RATE, UNITS, LABELS) and, with analog values, ANALOG.
C3dWriter trial(std::vector<std::string> labels, int frames, double scale = -0.1) {
  C3dWriter w;
  w.points = static_cast<int>(labels.size());
  w.scale = scale;
  w.last_frame = w.first_frame + frames - 1;
  for (int f = 0; f < frames; ++f) {
    std::vector<Sample> frame;
    for (int p = 0; p < w.points; ++p) {
      frame.push_back({100.0 * p + f, 200.0 - 2 * f, 900.0 + p, 1});
      if (p == 1 && f % 2 == 1) frame.back() = {0, 0, 0, -1};
    }
    w.frames.push_back(frame);
  }
  w.group(kPoint, "POINT");
  w.numbers(kPoint, "USED", 2, {static_cast<double>(w.points)});
  w.numbers(kPoint, "FRAMES", 2, {static_cast<double>(frames)});
  w.numbers(kPoint, "DATA_START", 2, {0});
  w.numbers(kPoint, "SCALE", 4, {scale});
  w.numbers(kPoint, "RATE", 4, {w.rate});
  w.text(kPoint, "UNITS", {"mm"}, 4);
  std::size_t length = 8;
  for (const std::string& l : labels) length = std::max(length, l.size());
  w.text(kPoint, "LABELS", labels, static_cast<int>(length));
  return w;
}

C3dWriter three_markers(double scale = -0.1) { return trial({"LFHD", "RFHD", "C7"}, 4, scale); }

// adds `channels` analog channels sampled `per_frame` times per frame
void add_analog(C3dWriter& w, int channels, int per_frame) {
  w.analog_per_frame = channels * per_frame;
  w.group(kAnalog, "ANALOG");
  w.numbers(kAnalog, "USED", 2, {static_cast<double>(channels)});
  w.numbers(kAnalog, "RATE", 4, {w.rate * per_frame});
}

io::C3dTrial parse(const std::string& bytes) { return io::parse_c3d(bytes, "trial.c3d"); }

// the message of the refusal, which must start with the source name
std::string refusal(const std::string& bytes) {
  try {
    parse(bytes);
  } catch (const io::C3dError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("trial.c3d: ", 0), 0u) << what;
    return what;
  }
  ADD_FAILURE() << "the file was read";
  return "";
}

#define EXPECT_REFUSED(bytes, ...)                                                          \
  do {                                                                                      \
    const std::string message_ = refusal(bytes);                                            \
    for (const char* part_ : {__VA_ARGS__}) {                                               \
      EXPECT_NE(message_.find(part_), std::string::npos) << part_ << "\n in: " << message_; \
    }                                                                                       \
  } while (0)

void put16(std::string& bytes, std::size_t at, int v) { bytes.replace(at, 2, le16(v)); }

// ---------------------------------------------------------------------------------------------
// the shared files

// x, y, z and residual of sample (frame, point) read straight from an Intel float file's bytes
std::array<float, 4> raw_sample(const std::string& bytes, int points, int analog, int f, int p) {
  const std::size_t data =
      (static_cast<std::uint8_t>(bytes[16]) | static_cast<std::uint8_t>(bytes[17]) << 8) - 1;
  const std::size_t at = data * 512 + (f * (4 * points + analog) + 4 * p) * 4;
  std::array<float, 4> v{};
  std::memcpy(v.data(), bytes.data() + at, sizeof v);
  return v;
}

TEST(C3dFiles, CmuMaleFullBodyHas41PrefixedMarkers) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string path = c3d_data_dir() + "/cmu_85_02.c3d";
  const io::C3dTrial t = io::read_c3d(path);
  EXPECT_EQ(t.point_count(), 41);
  EXPECT_EQ(t.frame_count(), 810);
  EXPECT_EQ(t.first_frame, 1);
  EXPECT_DOUBLE_EQ(t.rate_hz, 120.0);
  EXPECT_EQ(t.units, "mm");
  EXPECT_DOUBLE_EQ(t.to_metres, 1e-3);
  EXPECT_EQ(t.subject, "Male");
  EXPECT_EQ(t.labels.front(), "LFWT");
  EXPECT_EQ(t.positions.size(), 810u * 41u);
  EXPECT_EQ(t.missing_fraction(), 0.0);
  EXPECT_TRUE(t.warnings.empty());
  const int head = t.find("LFHD");
  ASSERT_GE(head, 0);
  EXPECT_EQ(t.find("Male:LFHD"), head);
  EXPECT_EQ(t.find("Female:LFHD"), -1);
  EXPECT_EQ(t.find("NOPE"), -1);
  // first marker of frame 0: (116.398, 1075.617, 991.908) mm in the file
  EXPECT_TRUE(t.position(0, 0).isApprox(Eigen::Vector3d(0.116398, 1.075617, 0.991908), 1e-5));
  // a second path: every sample equals the file's floats in metres, and stays in a 10 m lab
  const std::string bytes = slurp(path);
  for (int f = 0; f < t.frame_count(); f += 101) {
    for (int p = 0; p < t.point_count(); ++p) {
      const auto raw = raw_sample(bytes, 41, 0, f, p);
      EXPECT_NEAR(t.position(f, p).y(), raw[1] * 1e-3, 1e-9);
      EXPECT_LT(t.position(f, p).norm(), 10.0);
    }
  }
  // the head is above the waist
  EXPECT_GT(t.position(0, head).z(), t.position(0, t.find("LFWT")).z() + 0.3);
}

TEST(C3dFiles, OpensimWalking5SkipsForcePlateAnalogAndKeepsItsGaps) {
  PINDRAG_REQUIRE_DATA_DIR();
  const std::string path = c3d_data_dir() + "/opensim_walking5.c3d";
  const io::C3dTrial t = io::read_c3d(path);
  EXPECT_EQ(t.point_count(), 40);
  EXPECT_EQ(t.frame_count(), 1103);
  EXPECT_DOUBLE_EQ(t.rate_hz, 250.0);
  EXPECT_EQ(t.units, "mm");
  EXPECT_EQ(t.subject, "");
  EXPECT_EQ(t.labels.front(), "LTH3");
  EXPECT_GE(t.find("C7"), 0);
  EXPECT_NEAR(t.missing_fraction(), 0.455, 0.01);
  EXPECT_NEAR(t.time(250), 1.0, 1e-12);
  // a second path: 12 channels × 8 analog samples follow each frame's 40 points
  const std::string bytes = slurp(path);
  int missing = 0;
  for (int f = 0; f < t.frame_count(); ++f) {
    for (int p = 0; p < t.point_count(); ++p) {
      const auto raw = raw_sample(bytes, 40, 96, f, p);
      ASSERT_EQ(t.is_present(f, p), raw[3] >= 0) << f << " " << p;
      if (!t.is_present(f, p)) {
        ++missing;
        EXPECT_EQ(t.position(f, p), Eigen::Vector3d::Zero());
        continue;
      }
      EXPECT_NEAR(t.position(f, p).x(), raw[0] * 1e-3, 1e-9);
      EXPECT_NEAR(t.position(f, p).z(), raw[2] * 1e-3, 1e-9);
      EXPECT_LT(t.position(f, p).norm(), 10.0);
    }
  }
  EXPECT_EQ(missing, 20082);
}

TEST(C3dFiles, MissingOrOversizedFilesAreFileErrors) {
  EXPECT_THROW(io::read_c3d("/nonexistent/trial.c3d"), io::FileError);
  try {
    io::read_c3d(fixtures::source_dir());
    ADD_FAILURE() << "a directory was read";
  } catch (const io::FileError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// synthetic files

void expect_three_markers(const io::C3dTrial& t, double tolerance) {
  ASSERT_EQ(t.frame_count(), 4);
  ASSERT_EQ(t.point_count(), 3);
  EXPECT_EQ(t.labels, (std::vector<std::string>{"LFHD", "RFHD", "C7"}));
  EXPECT_EQ(t.positions.size(), 12u);
  EXPECT_EQ(t.present.size(), 12u);
  for (int f = 0; f < 4; ++f) {
    for (int p = 0; p < 3; ++p) {
      const bool gap = p == 1 && f % 2 == 1;
      EXPECT_EQ(t.is_present(f, p), !gap) << f << " " << p;
      const Eigen::Vector3d expected =
          gap ? Eigen::Vector3d::Zero() : Eigen::Vector3d(100.0 * p + f, 200.0 - 2 * f, 900.0 + p);
      EXPECT_LT((t.position(f, p) - 1e-3 * expected).norm(), tolerance) << f << " " << p;
    }
  }
  EXPECT_DOUBLE_EQ(t.missing_fraction(), 2.0 / 12.0);
}

TEST(C3dSynthetic, FloatDataIsReadAsWritten) {
  C3dWriter w = three_markers(-0.1);
  const io::C3dTrial t = parse(w.bytes());
  expect_three_markers(t, 1e-9);
  EXPECT_DOUBLE_EQ(t.rate_hz, 100);
  EXPECT_EQ(t.first_frame, 1);
  EXPECT_THROW(t.position(4, 0), std::out_of_range);
  EXPECT_THROW(t.is_present(0, -1), std::out_of_range);
}

TEST(C3dSynthetic, IntegerDataIsScaledBySCALE) {
  C3dWriter w = three_markers(0.05);  // int16 × 0.05 mm
  expect_three_markers(parse(w.bytes()), 0.025e-3);
}

TEST(C3dSynthetic, DecFilesReadVaxFloats) {
  // hand-encoded VAX F_floating words: 120 = 0.9375 × 2^7 → 0x43F0 0x0000; -2.5 = −0.625 × 2^2
  // → 0xC120 0x0000 (bytes in file order, each word little-endian)
  EXPECT_EQ(vax_bytes(120), std::string("\xF0\x43\x00\x00", 4));
  EXPECT_EQ(vax_bytes(-2.5), std::string("\x20\xC1\x00\x00", 4));
  EXPECT_EQ(vax_bytes(1), std::string("\x80\x40\x00\x00", 4));
  C3dWriter w = three_markers(-0.1);
  w.processor = 85;
  w.find("RATE")->raw = std::string("\xF0\x43\x00\x00", 4);
  std::string bytes = w.bytes();
  // frame 0, point 0, x: -2.5 mm
  const std::size_t data = (static_cast<std::uint8_t>(bytes[16]) - 1u) * 512;
  bytes.replace(data, 4, std::string("\x20\xC1\x00\x00", 4));
  const io::C3dTrial t = parse(bytes);
  EXPECT_DOUBLE_EQ(t.rate_hz, 120);
  EXPECT_DOUBLE_EQ(t.position(0, 0).x(), -2.5e-3);
  // the rest as an Intel file holds it
  C3dWriter intel = three_markers(-0.1);
  const io::C3dTrial i = parse(intel.bytes());
  for (std::size_t k = 1; k < t.positions.size(); ++k) {
    EXPECT_LT((t.positions[k] - i.positions[k]).norm(), 1e-9) << k;
  }
  EXPECT_EQ(t.present, i.present);
}

TEST(C3dSynthetic, DecIntegerDataIsLittleEndian) {
  C3dWriter w = three_markers(0.1);
  w.processor = 85;
  expect_three_markers(parse(w.bytes()), 0.05e-3);
}

// 70000 frames of one marker: the 16-bit header range and POINT:FRAMES cannot hold the count
C3dWriter long_trial() {
  C3dWriter w = trial({"M"}, 70000, 1.0);
  for (int f = 0; f < 70000; ++f) w.frames[f][0] = {static_cast<double>(f % 30000), 1, 2, 1};
  w.last_frame = 65535;
  w.find("FRAMES")->numbers = {65535};
  return w;
}

void expect_long(const io::C3dTrial& t, int first_frame) {
  ASSERT_EQ(t.frame_count(), 70000);
  EXPECT_EQ(t.first_frame, first_frame);
  EXPECT_DOUBLE_EQ(t.position(69999, 0).x(), (69999 % 30000) * 1e-3);
  EXPECT_DOUBLE_EQ(t.missing_fraction(), 0);
}

TEST(C3dSynthetic, TrialFieldsCountFramesBeyond65535) {
  C3dWriter w = long_trial();
  w.group(kTrial, "TRIAL");
  // 32-bit values as two 16-bit words, least significant first: 100000 … 169999
  w.numbers(kTrial, "ACTUAL_START_FIELD", 2, {100000 & 0xffff, 1});
  w.numbers(kTrial, "ACTUAL_END_FIELD", 2, {169999 & 0xffff, 2});
  expect_long(parse(w.bytes()), 100000);
  // POINT:FRAMES wrapped around 16 bits instead of saturated: the same
  w.find("FRAMES")->numbers = {70000 - 65536};
  expect_long(parse(w.bytes()), 100000);
}

TEST(C3dSynthetic, LongFramesOrFloatFramesCountFramesBeyond65535) {
  C3dWriter w = long_trial();
  w.numbers(kPoint, "LONG_FRAMES", 4, {70000});
  expect_long(parse(w.bytes()), 1);
  C3dWriter f = long_trial();
  *f.find("FRAMES") = {kPoint, "FRAMES", 4, {}, {70000}, "", false};
  expect_long(parse(f.bytes()), 1);
}

TEST(C3dSynthetic, StaleTrialFieldsBelow65535FramesDoNotOverridePointFrames) {
  C3dWriter w = three_markers();
  w.group(kTrial, "TRIAL");
  w.numbers(kTrial, "ACTUAL_START_FIELD", 2, {1, 0});
  w.numbers(kTrial, "ACTUAL_END_FIELD", 2, {9, 0});
  expect_three_markers(parse(w.bytes()), 1e-9);
}

TEST(C3dSynthetic, Labels2ContinuesTheLabels) {
  C3dWriter w = three_markers();
  w.find("LABELS")->raw = "LFHD    RFHD    ";
  w.find("LABELS")->dims = {8, 2};
  w.text(kPoint, "LABELS2", {"C7", "EXTRA"}, 6);
  expect_three_markers(parse(w.bytes()), 1e-9);
}

TEST(C3dSynthetic, AnalogValuesBetweenFramesAreSkipped) {
  for (double scale : {-0.1, 0.1}) {
    C3dWriter w = three_markers(scale);
    add_analog(w, 3, 4);  // 3 channels at 4 × the point rate: 12 values per frame
    w.analog_value = 7777;
    expect_three_markers(parse(w.bytes()), 0.05e-3);
  }
  // NaN analog values are not looked at
  C3dWriter w = three_markers();
  add_analog(w, 2, 1);
  w.analog_value = kNaN;
  expect_three_markers(parse(w.bytes()), 1e-9);
}

TEST(C3dSynthetic, ASharedLabelPrefixBecomesTheSubject) {
  for (const std::string subject : {"Male", "male"}) {
    C3dWriter w = trial({subject + ":LFHD", subject + ":RFHD"}, 2);
    const io::C3dTrial t = parse(w.bytes());
    EXPECT_EQ(t.subject, subject);
    EXPECT_EQ(t.labels, (std::vector<std::string>{"LFHD", "RFHD"}));
    EXPECT_EQ(t.find(subject + ":RFHD"), 1);
    EXPECT_EQ(t.find("RFHD"), 1);
  }
  // prefixes that differ, or that not every label has, stay in the labels
  for (const std::vector<std::string>& labels :
       {std::vector<std::string>{"Male:LFHD", "Female:LFHD"},
        std::vector<std::string>{"Male:LFHD", "RFHD"}, std::vector<std::string>{":A", ":B"}}) {
    const io::C3dTrial t = parse(trial(labels, 1).bytes());
    EXPECT_EQ(t.subject, "");
    EXPECT_EQ(t.labels, labels);
  }
}

TEST(C3dSynthetic, UnitsConvertToMetres) {
  for (const auto& [units, metres] :
       std::vector<std::pair<std::string, double>>{{"mm", 1e-3}, {"cm", 1e-2}, {"m", 1.0}}) {
    C3dWriter w = three_markers();
    w.find("UNITS")->raw = units + "  ";
    w.find("UNITS")->dims = {static_cast<int>(units.size()) + 2};
    const io::C3dTrial t = parse(w.bytes());
    EXPECT_EQ(t.units, units);
    EXPECT_DOUBLE_EQ(t.to_metres, metres);
    EXPECT_NEAR(t.position(0, 2).z(), 902 * metres, 1e-9);
  }
  C3dWriter w = three_markers();
  w.erase("UNITS");
  const io::C3dTrial t = parse(w.bytes());
  EXPECT_EQ(t.units, "mm");
  ASSERT_EQ(t.warnings.size(), 1u);
  EXPECT_NE(t.warnings[0].find("POINT:UNITS is absent"), std::string::npos) << t.warnings[0];
}

TEST(C3dSynthetic, ZeroSamplesAreGapsAndPresentZeroResidualsAreKept) {
  C3dWriter w = three_markers();
  w.frames[0][0] = {0, 0, 0, 0};  // a gap filled with zeros
  w.frames[0][2].residual = 0;    // interpolated, still a sample
  const io::C3dTrial t = parse(w.bytes());
  EXPECT_FALSE(t.is_present(0, 0));
  EXPECT_TRUE(t.is_present(0, 2));
}

TEST(C3dSynthetic, ChainVariantsAreRead) {
  // locked records (negative name lengths), lower-case names, a parameter before its group,
  // parameters of an unknown group, the chain ended by offset 0, the data a block later
  C3dWriter w = three_markers();
  w.find("RATE")->locked = true;
  w.find("POINT")->locked = true;
  w.find("USED")->name = "used";
  w.records.insert(w.records.begin(), Record{9, "ORPHAN", 4, {}, {kNaN}, "", false});
  std::rotate(w.records.begin() + 1, w.records.begin() + 2, w.records.end());  // POINT last
  w.last_offset_zero = true;
  w.data_start = 4;
  expect_three_markers(parse(w.bytes()), 1e-9);
}

TEST(C3dSynthetic, HeaderValuesServeWhenParametersAreAbsent) {
  C3dWriter w = three_markers();
  w.first_frame = 11;
  w.last_frame = 14;
  for (const char* name : {"FRAMES", "DATA_START", "SCALE", "RATE", "USED"}) w.erase(name);
  w.rate = 50;
  const io::C3dTrial t = parse(w.bytes());
  expect_three_markers(t, 1e-9);
  EXPECT_EQ(t.first_frame, 11);
  EXPECT_DOUBLE_EQ(t.rate_hz, 50);
}

TEST(C3dSynthetic, NoPointsGivesAnEmptyTrialWithItsFrames) {
  C3dWriter w = trial({}, 3);
  w.erase("LABELS");
  const io::C3dTrial t = parse(w.bytes());
  EXPECT_EQ(t.frame_count(), 3);
  EXPECT_EQ(t.point_count(), 0);
  EXPECT_TRUE(t.positions.empty());
  EXPECT_EQ(t.missing_fraction(), 0);
}

TEST(C3dSynthetic, AClipBudgetIsAppliedBeforeReadingSamples) {
  C3dWriter w = three_markers();
  io::ClipBudget budget;
  budget.max_frames = 3;
  budget.frames_setting = "--max-frames";
  try {
    io::parse_c3d(w.bytes(), "trial.c3d", budget);
    ADD_FAILURE() << "the budget was not applied";
  } catch (const io::C3dError& e) {
    EXPECT_NE(std::string(e.what()).find("--max-frames"), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// malformed files

TEST(C3dMalformed, TruncatedFilesAreRefused) {
  const std::string bytes = three_markers().bytes();
  EXPECT_REFUSED(bytes.substr(0, bytes.size() - 1), "data: 4 frames of 3 points",
                 "need 192 bytes from block 3", "holds 191", "truncated");
  EXPECT_REFUSED(bytes.substr(0, 100), "header: the file is 100 bytes");
  EXPECT_REFUSED("", "header: the file is 0 bytes");
  EXPECT_REFUSED(bytes.substr(0, 600),
                 "parameter section: 1 blocks from block 2 end at byte 1024, beyond the end of the "
                 "file (600 bytes)");
  EXPECT_REFUSED(bytes.substr(0, 512), "header: parameter block 2 is beyond the file (1 blocks)");
}

TEST(C3dMalformed, NotAC3dFileIsRefusedByItsKey) {
  std::string bytes = three_markers().bytes();
  bytes[1] = 'x';
  EXPECT_REFUSED(bytes, "header: byte 2 is 120", "not a C3D file?");
  bytes = three_markers().bytes();
  bytes[0] = 1;
  EXPECT_REFUSED(bytes, "header: parameter block 1", "block 1 is the header");
}

TEST(C3dMalformed, DataStartBeyondTheFileIsRefused) {
  std::string bytes = three_markers().bytes();
  put16(bytes, 16, 900);
  EXPECT_REFUSED(bytes, "POINT:DATA_START is 3 but the header's data start block is 900");
  C3dWriter w = three_markers();
  w.erase("DATA_START");
  bytes = w.bytes();
  put16(bytes, 16, 900);
  EXPECT_REFUSED(bytes, "header: data start block 900 is beyond the file (3 blocks)");
  put16(bytes, 16, 2);
  EXPECT_REFUSED(bytes, "header: data start block 2 is not after the parameter section");
  put16(bytes, 16, 0);
  EXPECT_REFUSED(bytes, "header: data start block 0 is not after the parameter section");
}

TEST(C3dMalformed, CountsBeyondTheFileAreRefusedWithoutAllocating) {
  C3dWriter w = three_markers();
  w.find("FRAMES")->numbers = {60000};
  EXPECT_REFUSED(w.bytes(), "data: 60000 frames of 3 points", "truncated");
  // 4·10^9 frames from the TRIAL fields
  w.find("FRAMES")->numbers = {65535};
  w.group(kTrial, "TRIAL");
  w.numbers(kTrial, "ACTUAL_START_FIELD", 2, {1, 0});
  w.numbers(kTrial, "ACTUAL_END_FIELD", 2, {0xffff, 0xffff});
  EXPECT_REFUSED(w.bytes(), "TRIAL:ACTUAL_START_FIELD/ACTUAL_END_FIELD gives 4294967295 frames",
                 "kMaxC3dFrames");
  w.find("ACTUAL_END_FIELD")->numbers = {0, 100};  // 6553600 frames, 1.2 KB of data
  EXPECT_REFUSED(w.bytes(), "data: 6553600 frames", "truncated");
  C3dWriter f = three_markers();
  f.find("FRAMES")->type = 4;
  f.find("FRAMES")->numbers = {1e12};
  EXPECT_REFUSED(f.bytes(), "POINT:FRAMES gives 999999995904 frames", "kMaxC3dFrames");
  f.find("FRAMES")->numbers = {2.5};
  EXPECT_REFUSED(f.bytes(), "POINT:FRAMES is 2.5 (rule: a whole number >= 0)");
  // analog values that the file cannot hold
  std::string a = three_markers().bytes();
  put16(a, 4, 60000);
  EXPECT_REFUSED(a, "60000 analog values", "truncated");
}

TEST(C3dMalformed, ScaleMustBeFiniteAndNonZero) {
  C3dWriter w = three_markers();
  w.find("SCALE")->numbers = {kNaN};
  EXPECT_REFUSED(w.bytes(), "POINT:SCALE is NaN (rule: a finite number)");
  w.find("SCALE")->numbers = {0};
  EXPECT_REFUSED(w.bytes(), "POINT:SCALE is 0 (rule: non-zero");
  w.find("SCALE")->numbers = {0.1};
  EXPECT_REFUSED(w.bytes(), "POINT:SCALE 0.100000001 and the header's scale factor -0.100000001",
                 "differ in sign");
  w.erase("SCALE");
  w.scale = kNaN;
  EXPECT_REFUSED(w.bytes(), "header: scale factor is NaN");
}

TEST(C3dMalformed, RateMustBePositive) {
  C3dWriter w = three_markers();
  w.find("RATE")->numbers = {0};
  EXPECT_REFUSED(w.bytes(), "trial.c3d: POINT:RATE is 0 (rule: the frame rate must be positive)");
  w.find("RATE")->numbers = {-120};
  EXPECT_REFUSED(w.bytes(), "POINT:RATE is -120 (rule: the frame rate must be positive)");
  w.find("RATE")->numbers = {std::numeric_limits<double>::infinity()};
  EXPECT_REFUSED(w.bytes(), "POINT:RATE is infinite");
  w.find("RATE")->numbers = {1e9};
  EXPECT_REFUSED(w.bytes(), "POINT:RATE is 1e+09 Hz", "kMaxC3dRateHz");
  w.erase("RATE");
  w.rate = 0;
  EXPECT_REFUSED(w.bytes(), "header: frame rate is 0 (rule: the frame rate must be positive)");
}

TEST(C3dMalformed, LabelsMustCoverEveryPoint) {
  std::vector<std::string> labels;
  for (int i = 0; i < 41; ++i) labels.push_back("M" + std::to_string(i));
  C3dWriter w = trial(labels, 2);
  w.find("LABELS")->dims = {8, 38};
  w.find("LABELS")->raw.resize(8 * 38);
  EXPECT_REFUSED(w.bytes(), "POINT:LABELS has 38 labels but POINT:USED is 41",
                 "LABELS2, LABELS3... continue the list");
  w.text(kPoint, "LABELS2", {"A", "B"}, 4);
  EXPECT_REFUSED(w.bytes(), "POINT:LABELS with LABELS2 has 40 labels but POINT:USED is 41");
  w.erase("LABELS");
  EXPECT_REFUSED(w.bytes(), "POINT:LABELS is missing but POINT:USED is 41");
  C3dWriter n = three_markers();
  n.find("LABELS")->type = 2;
  n.find("LABELS")->raw.resize(2 * 8 * 3);
  EXPECT_REFUSED(n.bytes(), "POINT:LABELS has type 2 (rule: text is type -1 char)");
}

TEST(C3dMalformed, HeaderAndParametersMustAgree) {
  C3dWriter w = three_markers();
  w.points = 2;
  EXPECT_REFUSED(w.bytes(), "POINT:USED is 3 but the header's point count is 2");
  C3dWriter a = three_markers();
  add_analog(a, 3, 4);
  a.analog_per_frame = 6;
  EXPECT_REFUSED(a.bytes(), "header: 6 analog values per frame, but ANALOG:USED 3",
                 "ANALOG:RATE 400 / POINT:RATE 100 = 12");
  C3dWriter h = three_markers();
  h.erase("FRAMES");
  h.first_frame = 10;
  h.last_frame = 3;
  EXPECT_REFUSED(h.bytes(), "header: last frame 3 is before first frame 10");
}

TEST(C3dMalformed, BigEndianAndUnknownProcessorsAreRefused) {
  C3dWriter w = three_markers();
  w.processor = 86;
  EXPECT_REFUSED(w.bytes(), "parameter section: processor type 86 (MIPS, big-endian)",
                 "Intel (84) and DEC (85)");
  w.processor = 0;
  EXPECT_REFUSED(w.bytes(), "processor type 0 is unknown");
}

TEST(C3dMalformed, AParameterChainLeavingItsSectionIsRefused) {
  C3dWriter w = three_markers();
  std::string bytes = w.bytes();
  const std::size_t rate = w.record_at.at("POINT:RATE");
  put16(bytes, rate + 2 + 4, 30000);  // the offset after the 4-char name
  EXPECT_REFUSED(bytes, "parameter section: record 'RATE'", "next-record offset 30000",
                 "stays inside the parameter blocks");
  put16(bytes, rate + 2 + 4, -40);  // backwards: a loop
  EXPECT_REFUSED(bytes, "next-record offset -40", "moves forward");
  put16(bytes, rate + 2 + 4, 3);  // inside its own data
  EXPECT_REFUSED(bytes, "next-record offset 3");
  // the last record points to a record that runs past the section's end (byte 1024)
  bytes = w.bytes();
  const std::size_t labels_link = w.record_at.at("POINT:LABELS") + 2 + 6;
  put16(bytes, labels_link, static_cast<int>(1023 - labels_link));
  bytes[1023] = 5;
  EXPECT_REFUSED(bytes, "parameter section: byte 1023: the record header runs past the end");
  put16(bytes, labels_link, static_cast<int>(1020 - labels_link));
  bytes[1020] = 5;
  bytes[1021] = 1;
  EXPECT_REFUSED(bytes, "parameter section: byte 1020: the record's name runs past the end");
  // a section claiming more blocks than the file has
  bytes = w.bytes();
  bytes[512 + 2] = 9;
  EXPECT_REFUSED(bytes,
                 "parameter section: 9 blocks from block 2 end at byte 5120, beyond the end");
  bytes[512 + 2] = 0;
  EXPECT_REFUSED(bytes, "parameter section: its block count is 0");
}

TEST(C3dMalformed, BadTypesAndDimensionsAreRefused) {
  C3dWriter w = three_markers();
  std::string bytes = w.bytes();
  const std::size_t rate_body = w.record_at.at("POINT:RATE") + 2 + 4 + 2;
  bytes[rate_body + 1] = -1;
  EXPECT_REFUSED(bytes, "parameter section: POINT:RATE: -1 dimensions (rule: 0 to 7)");
  bytes[rate_body + 1] = 8;
  EXPECT_REFUSED(bytes, "POINT:RATE: 8 dimensions (rule: 0 to 7)");
  bytes = w.bytes();
  bytes[rate_body] = 3;
  EXPECT_REFUSED(bytes, "POINT:RATE: type 3 (rule: -1 char, 1 byte, 2 int16 or 4 float)");
  // zero dimensions: no value where one is needed
  w.find("RATE")->dims = {0};
  w.find("RATE")->numbers = {};
  EXPECT_REFUSED(w.bytes(), "POINT:RATE has no value (dimensions [0]");
  // dimensions whose data cannot fit the section
  C3dWriter d = three_markers();
  bytes = d.bytes();
  const std::size_t labels_body = d.record_at.at("POINT:LABELS") + 2 + 6 + 2;
  bytes[labels_body + 2] = static_cast<char>(200);
  bytes[labels_body + 3] = static_cast<char>(200);
  EXPECT_REFUSED(bytes, "POINT:LABELS: dimensions [200, 200]", "need 40000 bytes");
  // a group id of 0
  bytes = d.bytes();
  bytes[d.record_at.at("POINT:RATE") + 1] = 0;
  EXPECT_REFUSED(bytes, "record 'RATE' has id 0");
}

TEST(C3dMalformed, NumbersMustBeNumbersAndPresentSamplesFinite) {
  C3dWriter w = three_markers();
  w.find("RATE")->type = -1;
  w.find("RATE")->raw = "abcd";
  EXPECT_REFUSED(w.bytes(), "POINT:RATE is text");
  C3dWriter u = three_markers();
  u.find("UNITS")->raw = "ft  ";
  EXPECT_REFUSED(u.bytes(), "POINT:UNITS is 'ft' (rule: mm, cm or m)");
  C3dWriter s = three_markers();
  s.frames[2][1] = {1, kNaN, 3, 1};
  EXPECT_REFUSED(s.bytes(), "data: frame 2 (file frame 3), point 1 'RFHD': Y is NaN",
                 "a present sample is finite");
  s.frames[2][1] = {kNaN, kNaN, kNaN, -1};  // missing: the coordinates are not looked at
  EXPECT_NO_THROW(parse(s.bytes()));
  s.frames[2][1].residual = kNaN;
  EXPECT_REFUSED(s.bytes(), "point 1 'RFHD': the residual word is NaN (rule: a finite number)");
}

// ---------------------------------------------------------------------------------------------
// fuzzing seeds (tests/fixtures/c3d): this writer's output, rewritten when
// PINDRAG_UPDATE_C3D_SEEDS is set

std::map<std::string, std::function<std::string()>> seeds() {
  return {
      {"intel_float_gaps.c3d", [] { return three_markers(-0.1).bytes(); }},
      {"intel_int16_analog.c3d",
       [] {
         C3dWriter w = trial({"Male:LFHD", "Male:RFHD"}, 3, 0.1);
         add_analog(w, 2, 2);
         return w.bytes();
       }},
      {"dec_float_labels2_trial.c3d",
       [] {
         C3dWriter w = three_markers(-0.1);
         w.processor = 85;
         w.find("LABELS")->raw = "LFHD    RFHD    ";
         w.find("LABELS")->dims = {8, 2};
         w.text(kPoint, "LABELS2", {"C7"}, 4);
         w.group(kTrial, "TRIAL");
         w.numbers(kTrial, "ACTUAL_START_FIELD", 2, {1, 0});
         w.numbers(kTrial, "ACTUAL_END_FIELD", 2, {4, 0});
         return w.bytes();
       }},
  };
}

TEST(C3dSeeds, FuzzSeedsAreTheWritersOutputAndRead) {
  const bool update = std::getenv("PINDRAG_UPDATE_C3D_SEEDS") != nullptr;
  for (const auto& [name, make] : seeds()) {
    const std::string bytes = make();
    const std::string path = seeds_dir() + "/" + name;
    if (update) {
      std::filesystem::create_directories(seeds_dir());
      std::ofstream(path, std::ios::binary) << bytes;
    }
    EXPECT_LT(bytes.size(), 4096u) << name;
    EXPECT_EQ(slurp(path), bytes) << name << " differs from the writer's output; rerun with "
                                  << "PINDRAG_UPDATE_C3D_SEEDS=1 if the writer changed";
    const io::C3dTrial t = io::read_c3d(path);
    EXPECT_GT(t.frame_count(), 0) << name;
  }
}

}  // namespace
