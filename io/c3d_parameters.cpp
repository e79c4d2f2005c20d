// Numbers and the parameter section of a C3D file (io/c3d_format.hpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>

#include "io/c3d.hpp"
#include "io/c3d_format.hpp"

namespace io::c3d_detail {

namespace {

constexpr std::size_t kMaxEmptyStrings = 65536;

char upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c; }

// a record's name in upper case; bytes that are not printable ASCII (never in a name this reader
// looks up) become '?', so messages stay text
std::string name_of(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = (c >= 0x20 && c < 0x7f) ? upper(c) : '?';
  return out;
}

int s8(std::string_view bytes, std::size_t at) { return static_cast<std::int8_t>(bytes[at]); }
int byte_at(std::string_view bytes, std::size_t at) { return static_cast<std::uint8_t>(bytes[at]); }

std::string trim_right(std::string_view s) {
  std::size_t n = s.size();
  while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\0')) --n;
  return std::string(s.substr(0, n));
}

std::string dims_text(const std::vector<int>& dims) {
  std::string out = "[";
  for (std::size_t i = 0; i < dims.size(); ++i) out += (i ? ", " : "") + std::to_string(dims[i]);
  return out + "]";
}

// One walk along the chain of records (C3D User Guide, "Group Format" and "Parameter Format"):
// name length (negative: locked), id (negative: a group, positive: a parameter of group −id),
// name, a signed 16-bit offset from itself to the next record (0: the last), then a group's
// description, or a parameter's type, dimensions, data and description.
class Walker {
 public:
  Walker(std::string_view file, std::size_t begin, std::size_t end, const std::string& source)
      : file_(file), end_(end), at_(begin), source_(source) {}

  std::vector<Parameter> walk() {
    // a zero name length also ends the chain (Vicon ends it so, after the last offset)
    while (at_ < end_) {
      if (at_ + 2 > end_) fail_at("the record header runs past the end of the section");
      const int length = s8(file_, at_);
      const int id = s8(file_, at_ + 1);
      if (length == 0) break;
      const std::size_t n = static_cast<std::size_t>(std::abs(length));
      const std::size_t link = at_ + 2 + n;  // the next-record offset
      if (link + 2 > end_) fail_at("the record's name runs past the end of the section");
      const std::string name = name_of(file_.substr(at_ + 2, n));
      if (id == 0) {
        fail(source_, "parameter section: byte " + std::to_string(at_) + ": record " +
                          shown_text(name) +
                          " has id 0 (rule: a group's id is -1 to -127, a parameter's 1 to 127)");
      }
      const int offset = i16(file_, link);
      const std::size_t used = id < 0 ? group(-id, name, link + 2) : parameter(id, name, link + 2);
      if (offset == 0) break;
      next(link, offset, used, name);
    }
    std::vector<Parameter> out;
    for (Raw& r : raw_) {
      const auto g = groups_.find(r.id);
      if (g == groups_.end()) continue;
      r.p.group = g->second;
      out.push_back(std::move(r.p));
    }
    return out;
  }

 private:
  struct Raw {
    int id;
    Parameter p;
  };

  [[noreturn]] void fail_at(const std::string& what) const {
    fail(source_, "parameter section: byte " + std::to_string(at_) + ": " + what +
                      " (rule: records stay inside the parameter blocks)");
  }

  std::string label(int id, const std::string& name) const {
    const auto g = groups_.find(id);
    if (g != groups_.end()) return g->second + ":" + name;
    return "parameter " + shown_text(name) + " of group " + std::to_string(id);
  }

  std::size_t group(int id, const std::string& name, std::size_t after_link) {
    groups_.emplace(id, name);  // the first group with an id counts
    return after_link;
  }

  // reads type, dimensions and the data's extent; returns the end of the data
  std::size_t parameter(int id, const std::string& name, std::size_t at) {
    const std::string what = "parameter section: " + label(id, name);
    if (at + 2 > end_) fail(source_, what + ": its type runs past the end of the section");
    Parameter p;
    p.name = name;
    p.type = s8(file_, at);
    if (p.type != -1 && p.type != 1 && p.type != 2 && p.type != 4) {
      fail(source_, what + ": type " + std::to_string(p.type) +
                        " (rule: -1 char, 1 byte, 2 int16 or 4 float)");
    }
    const int ndims = s8(file_, at + 1);
    if (ndims < 0 || ndims > 7) {
      fail(source_, what + ": " + std::to_string(ndims) + " dimensions (rule: 0 to 7)");
    }
    if (at + 2 + ndims > end_) fail(source_, what + ": its dimensions run past the section");
    for (int d = 0; d < ndims; ++d) p.dims.push_back(byte_at(file_, at + 2 + d));
    // at most 255^7 × 4 bytes: no overflow in 64 bits
    const std::uint64_t bytes = static_cast<std::uint64_t>(std::abs(p.type)) * p.elements();
    const std::size_t data = at + 2 + ndims;
    if (bytes > end_ - data) {
      fail(source_, what + ": dimensions " + dims_text(p.dims) + " of " +
                        std::to_string(std::abs(p.type)) + "-byte elements need " +
                        std::to_string(bytes) + " bytes but the section has " +
                        std::to_string(end_ - data) + " left (rule: data stays inside the " +
                        "parameter blocks)");
    }
    p.data = file_.substr(data, static_cast<std::size_t>(bytes));
    raw_.push_back({id, std::move(p)});
    return data + static_cast<std::size_t>(bytes);
  }

  void next(std::size_t link, int offset, std::size_t used, const std::string& name) {
    const auto target = static_cast<std::int64_t>(link) + offset;
    if (target < static_cast<std::int64_t>(used) || target > static_cast<std::int64_t>(end_)) {
      fail(source_, "parameter section: record " + shown_text(name) + " at byte " +
                        std::to_string(at_) + ": its next-record offset " + std::to_string(offset) +
                        " points to byte " + std::to_string(target) + ", outside bytes " +
                        std::to_string(used) + " to " + std::to_string(end_) +
                        " (rule: the chain moves forward past each record and stays inside the " +
                        "parameter blocks)");
    }
    at_ = static_cast<std::size_t>(target);
  }

  std::string_view file_;
  std::size_t end_;
  std::size_t at_;
  const std::string& source_;
  std::map<int, std::string> groups_;  // id (positive) → name
  std::vector<Raw> raw_;
};

}  // namespace

void fail(const std::string& source, const std::string& what) {
  throw C3dError(source + ": " + what);
}

std::string shown_text(std::string_view text) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += (c >= 0x20 && c < 0x7f) ? static_cast<char>(c) : '?';
  }
  if (text.size() > kMaxShown) out += "...";
  return out + "'";
}

std::string number_text(double v) {
  if (std::isnan(v)) return "NaN";
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

std::size_t blocks_in(std::size_t bytes) { return (bytes + kBlockBytes - 1) / kBlockBytes; }

std::uint16_t u16(std::string_view bytes, std::size_t at) {
  return static_cast<std::uint16_t>(static_cast<std::uint8_t>(bytes[at]) |
                                    (static_cast<std::uint8_t>(bytes[at + 1]) << 8));
}

std::int16_t i16(std::string_view bytes, std::size_t at) {
  return static_cast<std::int16_t>(u16(bytes, at));
}

double vax_f(std::uint16_t first, std::uint16_t second) {
  const bool negative = (first & 0x8000u) != 0;
  const int exponent = (first >> 7) & 0xff;
  if (exponent == 0) return negative ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  // 24-bit significand with the hidden bit: 0.1f = (2^23 + f) × 2^-24
  const std::uint32_t significand = 0x800000u | ((first & 0x7fu) << 16) | second;
  const double magnitude = std::ldexp(static_cast<double>(significand), exponent - 128 - 24);
  return negative ? -magnitude : magnitude;
}

double real(std::string_view bytes, std::size_t at, Processor processor) {
  if (processor == Processor::kDec) return vax_f(u16(bytes, at), u16(bytes, at + 2));
  const std::uint32_t bits = static_cast<std::uint32_t>(u16(bytes, at)) |
                             (static_cast<std::uint32_t>(u16(bytes, at + 2)) << 16);
  float f = 0;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

std::size_t Parameter::elements() const {
  std::size_t n = 1;
  for (int d : dims) n *= static_cast<std::size_t>(d);
  return n;
}

Parameters::Parameters(std::string_view file, std::size_t block, const std::string& source)
    : source_(source), first_block_(block) {
  // the section's own header: two reserved bytes, its block count, the processor type
  const std::size_t begin = (block - 1) * kBlockBytes;
  block_count_ = byte_at(file, begin + 2);
  const int processor = byte_at(file, begin + 3);
  if (processor == static_cast<int>(Processor::kMips)) {
    fail(source_, "parameter section: processor type 86 (MIPS, big-endian) is not supported " +
                      std::string("(rule: pindrag reads Intel (84) and DEC (85) files)"));
  }
  if (processor != static_cast<int>(Processor::kIntel) &&
      processor != static_cast<int>(Processor::kDec)) {
    fail(source_, "parameter section: processor type " + std::to_string(processor) +
                      " is unknown (rule: 84 Intel, 85 DEC or 86 MIPS)");
  }
  processor_ = static_cast<Processor>(processor);
  if (block_count_ == 0) {
    fail(source_, "parameter section: its block count is 0 (rule: at least 1 block)");
  }
  const std::size_t end = begin + block_count_ * kBlockBytes;
  if (end > file.size()) {
    fail(source_, "parameter section: " + std::to_string(block_count_) + " blocks from block " +
                      std::to_string(block) + " end at byte " + std::to_string(end) +
                      ", beyond the end of the file (" + std::to_string(file.size()) + " bytes)");
  }
  params_ = Walker(file, begin + 4, end, source_).walk();
  // by GROUP:NAME; the first of two with the same names counts
  for (std::size_t i = 0; i < params_.size(); ++i) index_.emplace(params_[i].field(), i);
}

const Parameter* Parameters::find(std::string_view group, std::string_view name) const {
  const auto it = index_.find(name_of(group) + ":" + name_of(name));
  return it == index_.end() ? nullptr : &params_[it->second];
}

const Parameter& Parameters::numeric(const Parameter& p) const {
  if (p.type == -1) {
    fail(source_, p.field() + " is text (rule: a number of type 1 byte, 2 int16 or 4 float)");
  }
  if (p.elements() == 0) {
    fail(source_, p.field() + " has no value (dimensions " + dims_text(p.dims) +
                      "; rule: at least one element)");
  }
  return p;
}

double Parameters::element(const Parameter& p, std::size_t i) const {
  switch (p.type) {
    case 1:
      return byte_at(p.data, i);
    case 2:
      return i16(p.data, 2 * i);
    default:
      return real(p.data, 4 * i, processor_);
  }
}

std::optional<double> Parameters::number(std::string_view group, std::string_view name) const {
  const Parameter* p = find(group, name);
  if (p == nullptr) return std::nullopt;
  const double v = element(numeric(*p), 0);
  if (!std::isfinite(v)) {
    fail(source_,
         p->field() + " is " + (std::isnan(v) ? "NaN" : "infinite") + " (rule: a finite number)");
  }
  return v;
}

std::optional<std::int64_t> Parameters::count(std::string_view group, std::string_view name) const {
  const Parameter* p = find(group, name);
  if (p == nullptr) return std::nullopt;
  numeric(*p);
  if (p->type == 2) return u16(p->data, 0);
  const double v = element(*p, 0);
  // 2^53: every whole number below is exact in a double
  if (!(v >= 0 && v <= 9007199254740992.0 && v == std::floor(v))) {
    fail(source_, p->field() + " is " + number_text(v) + " (rule: a whole number >= 0)");
  }
  return static_cast<std::int64_t>(v);
}

std::optional<std::int64_t> Parameters::long_count(std::string_view group,
                                                   std::string_view name) const {
  const Parameter* p = find(group, name);
  if (p == nullptr) return std::nullopt;
  if (p->type == 2 && p->elements() >= 2) {
    // least significant word first (C3D User Guide, "The TRIAL Group"; its formula's factor
    // 65535 is read as the 65536 that two 16-bit words of one 32-bit value mean)
    return static_cast<std::int64_t>(u16(p->data, 0)) +
           (static_cast<std::int64_t>(u16(p->data, 2)) << 16);
  }
  return count(group, name);
}

std::optional<std::vector<std::string>> Parameters::strings(std::string_view group,
                                                            std::string_view name) const {
  const Parameter* p = find(group, name);
  if (p == nullptr) return std::nullopt;
  if (p->type != -1) {
    fail(source_,
         p->field() + " has type " + std::to_string(p->type) + " (rule: text is type -1 char)");
  }
  // [length, n1, n2, ...]: n1 × n2 × ... strings of `length` chars; a scalar is one char
  const std::size_t length = p->dims.empty() ? 1 : static_cast<std::size_t>(p->dims[0]);
  std::size_t n = 1;
  for (std::size_t d = 1; d < p->dims.size(); ++d) n *= static_cast<std::size_t>(p->dims[d]);
  // empty strings take no bytes, so their number is bounded here instead: more than any count
  // of points (16 bits) is never needed
  if (length == 0) return std::vector<std::string>(std::min<std::size_t>(n, kMaxEmptyStrings));
  std::vector<std::string> out;
  out.reserve(n);  // n × length ≤ the data's size
  for (std::size_t i = 0; i < n; ++i) out.push_back(trim_right(p->data.substr(i * length, length)));
  return out;
}

}  // namespace io::c3d_detail
