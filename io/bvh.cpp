#include "io/bvh.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <stdexcept>
#include <system_error>
#include <unordered_map>
#include <unordered_set>

#include "io/atomic_file.hpp"
#include "core/configuration.hpp"
#include "core/data.hpp"
#include "core/kinematics.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

// ---------------------------------------------------------------------------------------------
// text helpers

inline bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

inline char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (lower(a[i]) != lower(b[i])) return false;
  }
  return true;
}

// a token as it appears in a message: quoted, at most 40 bytes, non-printable bytes as \xNN
std::string show(std::string_view s) {
  std::string out = "'";
  const size_t n = std::min<size_t>(s.size(), 40);
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c >= 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (s.size() > n) out += "...";
  return out + "'";
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

std::optional<BvhChannel> channel_from(std::string_view s) {
  static constexpr std::array<const char*, 6> kNames = {"xposition", "yposition", "zposition",
                                                         "xrotation", "yrotation", "zrotation"};
  for (size_t i = 0; i < kNames.size(); ++i) {
    if (iequals(s, kNames[i])) return static_cast<BvhChannel>(i);
  }
  return std::nullopt;
}

// ---------------------------------------------------------------------------------------------
// numbers

enum class NumberStatus { kOk, kNotANumber, kOutOfRange };

constexpr std::array<double, 23> kPow10 = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                           1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                           1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// The number that occupies exactly [b, e). Plain decimals with at most 15 significant digits and
// 22 decimals take the exact fast path (both m and 10^k are exact doubles, so m / 10^k is
// correctly rounded, as Clinger's fast path); anything else goes to std::from_chars.
NumberStatus parse_number(const char* b, const char* e, double& out) {
  const char* p = b;
  bool negative = false;
  if (p < e && (*p == '-' || *p == '+')) {
    negative = *p == '-';
    ++p;
  }
  const char* digits_begin = p;
  std::uint64_t m = 0;
  int significant = 0;
  int decimals = 0;
  bool fast = true;
  while (p < e && static_cast<unsigned>(*p - '0') < 10u) {
    m = m * 10 + static_cast<unsigned>(*p - '0');
    if (m != 0 && ++significant > 15) fast = false;
    ++p;
  }
  const bool int_digits = p != digits_begin;
  bool frac_digits = false;
  if (fast && p < e && *p == '.') {
    ++p;
    while (p < e && static_cast<unsigned>(*p - '0') < 10u) {
      m = m * 10 + static_cast<unsigned>(*p - '0');
      if (m != 0 && ++significant > 15) fast = false;
      ++decimals;
      frac_digits = true;
      ++p;
    }
  }
  if (fast && p == e && (int_digits || frac_digits) && decimals <= 22) {
    const double v = static_cast<double>(m) / kPow10[decimals];
    out = negative ? -v : v;
    return NumberStatus::kOk;
  }
  // general path: exponents, long mantissas, inf and nan (from_chars takes no leading '+')
  const char* q = b;
  if (q < e && *q == '+') {
    ++q;
    if (q < e && *q == '-') return NumberStatus::kNotANumber;
  }
  const auto r = std::from_chars(q, e, out);
  if (r.ec == std::errc::invalid_argument || r.ptr != e) return NumberStatus::kNotANumber;
  if (r.ec == std::errc::result_out_of_range) return NumberStatus::kOutOfRange;
  return NumberStatus::kOk;
}

// writes v in fixed notation with 6 decimals; never "-0.000000"
char* put_fixed(char* out, double v) {
  const auto r = std::to_chars(out, out + 400, v, std::chars_format::fixed, 6);
  if (std::signbit(v) && v > -1e-6 && r.ptr - out == 9 &&
      std::memcmp(out, "-0.000000", 9) == 0) {  // also -0.0 itself
    std::memcpy(out, "0.000000", 8);
    return out + 8;
  }
  return r.ptr;
}

// shortest exact fixed form, padded to at least 7 significant digits
std::string frame_time_text(double t) {
  char buf[512];
  const auto r = std::to_chars(buf, buf + sizeof buf, t, std::chars_format::fixed);
  std::string s(buf, r.ptr);
  int significant = 0;
  bool started = false;
  for (char c : s) {
    if (c >= '1' && c <= '9') started = true;
    if (started && c >= '0' && c <= '9') ++significant;
  }
  if (significant < 7) {
    if (s.find('.') == std::string::npos) s += '.';
    s.append(static_cast<size_t>(7 - significant), '0');
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// tokenizer for the hierarchy and the MOTION header: whitespace-separated words, with '{' and
// '}' always tokens of their own; counts lines and enforces the line-length limit

struct Token {
  std::string_view text;  // empty at the end of the input
  int line = 0;
  bool end() const { return text.empty(); }
};

class Tokenizer {
 public:
  Tokenizer(std::string_view text, const std::string& source) : text_(text), source_(source) {
    if (text_.size() >= 3 && std::memcmp(text_.data(), "\xEF\xBB\xBF", 3) == 0) pos_ = 3;
  }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw ModelError({source_ + ": line " + std::to_string(line) + ": " + what});
  }

  const Token& peek() {
    if (!peeked_) peeked_ = scan();
    return *peeked_;
  }
  Token next() {
    const Token t = peek();
    peeked_.reset();
    return t;
  }
  // byte offset just past the last consumed token (only valid with nothing peeked)
  size_t position() const { return pos_; }
  int line() const { return line_; }

 private:
  Token scan() {
    // skip blanks and newlines
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        check_line_length(pos_);
        ++line_;
        line_start_ = pos_ + 1;
        ++pos_;
      } else if (is_blank(c)) {
        ++pos_;
      } else {
        break;
      }
    }
    if (pos_ >= text_.size()) {
      check_line_length(pos_);
      return {{}, line_};
    }
    const size_t begin = pos_;
    const char c0 = text_[pos_];
    if (c0 == '{' || c0 == '}') {
      ++pos_;
      return {text_.substr(begin, 1), line_};
    }
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n' || is_blank(c) || c == '{' || c == '}') break;
      const auto u = static_cast<unsigned char>(c);
      if (u < 0x20 || u == 0x7f) {
        fail(line_, "byte " + show(std::string_view(&text_[pos_], 1)) +
                        " is a control character (rule: a BVH hierarchy is text; binary data?)");
      }
      ++pos_;
    }
    check_line_length(pos_);
    return {text_.substr(begin, pos_ - begin), line_};
  }

  void check_line_length(size_t at) const {
    if (at - line_start_ > kMaxBvhLineBytes) {
      fail(line_, "the line is longer than " + std::to_string(kMaxBvhLineBytes) +
                      " bytes (rule: kMaxBvhLineBytes)");
    }
  }

  std::string_view text_;
  const std::string& source_;
  size_t pos_ = 0;
  int line_ = 1;
  size_t line_start_ = 0;
  std::optional<Token> peeked_;
};

// ---------------------------------------------------------------------------------------------
// the parser

bool is_keyword(std::string_view s) {
  for (const char* k : {"ROOT", "JOINT", "End", "OFFSET", "CHANNELS", "MOTION", "HIERARCHY", "{",
                        "}"}) {
    if (iequals(s, k)) return true;
  }
  return false;
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& source)
      : text_(text), source_(source), tz_(text, source) {}

  BvhDocument parse() {
    hierarchy();
    motion();
    return std::move(doc_);
  }

 private:
  struct Open {
    int node;
    bool offset = false;
    bool channels = false;
    bool children = false;
  };

  [[noreturn]] void fail(int line, const std::string& what) const { tz_.fail(line, what); }

  std::string describe(int node) const {
    const BvhNode& n = doc_.nodes[node];
    if (n.is_end_site()) {
      return "End Site of '" + doc_.nodes[n.parent].name + "' (line " + std::to_string(n.line) +
             ")";
    }
    return std::string(n.kind == BvhNode::Kind::kRoot ? "ROOT" : "joint") + " '" + n.name +
           "' (line " + std::to_string(n.line) + ")";
  }

  void hierarchy() {
    Token t = tz_.next();
    if (t.end()) fail(t.line, "the file is empty (rule: a BVH file starts with HIERARCHY)");
    if (!iequals(t.text, "HIERARCHY")) {
      fail(t.line, "expected HIERARCHY, found " + show(t.text) +
                       " (rule: a BVH file starts with HIERARCHY)");
    }
    t = tz_.next();
    if (!iequals(t.text, "ROOT")) {
      if (t.end() || iequals(t.text, "MOTION") || iequals(t.text, "JOINT")) {
        fail(t.line, "missing ROOT (rule: the hierarchy starts with one ROOT joint)");
      }
      fail(t.line, "expected ROOT, found " + show(t.text) +
                       " (rule: the hierarchy starts with one ROOT joint)");
    }
    open_joint(BvhNode::Kind::kRoot, t.line);

    while (!stack_.empty()) {
      const int node = stack_.back().node;
      const bool end_site = doc_.nodes[node].is_end_site();
      t = tz_.next();
      if (t.end()) {
        fail(t.line, "the file ends inside " + describe(node) +
                         " (rule: every '{' is closed by '}'; truncated file?)");
      }
      if (iequals(t.text, "OFFSET")) {
        offset(node);
      } else if (iequals(t.text, "CHANNELS")) {
        if (end_site) {
          fail(t.line, describe(node) + " has CHANNELS (rule: an End Site has only an OFFSET)");
        }
        channels(node, t.line);
      } else if (iequals(t.text, "JOINT") || iequals(t.text, "End")) {
        if (end_site) {
          fail(t.line, show(t.text) + " inside " + describe(node) +
                           " (rule: an End Site has no children)");
        }
        if (!stack_.back().offset || !stack_.back().channels) {
          fail(t.line, describe(node) + " needs OFFSET and CHANNELS before its first child " +
                           "(rule: a joint lists OFFSET, CHANNELS, then its children)");
        }
        stack_.back().children = true;
        if (iequals(t.text, "JOINT")) {
          open_joint(BvhNode::Kind::kJoint, t.line);
        } else {
          open_end_site(t.line);
        }
      } else if (t.text == "}") {
        if (!stack_.back().offset) fail(t.line, describe(node) + " has no OFFSET");
        if (!end_site && !stack_.back().channels) {
          fail(t.line, describe(node) + " has no CHANNELS");
        }
        stack_.pop_back();
      } else if (iequals(t.text, "ROOT")) {
        fail(t.line, "a second ROOT inside " + describe(node) +
                         " (rule: one ROOT per file; ROOT is only the first joint)");
      } else if (iequals(t.text, "MOTION")) {
        fail(t.line, "MOTION inside " + describe(node) +
                         " (rule: every '{' is closed by '}' before MOTION)");
      } else if (channel_from(t.text)) {
        fail(t.line, "channel name " + show(t.text) + " after the CHANNELS of " + describe(node) +
                         " (rule: the CHANNELS count equals the channel names that follow)");
      } else {
        fail(t.line, "unexpected " + show(t.text) + " in " + describe(node) +
                         " (expected OFFSET, CHANNELS, JOINT, End Site or '}')");
      }
    }

    t = tz_.next();
    if (iequals(t.text, "ROOT")) {
      fail(t.line, "a second ROOT (rule: one skeleton per file; pindrag reads a single ROOT)");
    }
    if (t.end()) fail(t.line, "missing MOTION section after the hierarchy (truncated file?)");
    if (!iequals(t.text, "MOTION")) {
      fail(t.line, "expected MOTION after the hierarchy, found " + show(t.text));
    }
  }

  void open_joint(BvhNode::Kind kind, int line) {
    // the name: every word on the keyword's line up to '{'
    std::string name;
    while (!tz_.peek().end() && tz_.peek().line == line && tz_.peek().text != "{") {
      if (!name.empty()) name += ' ';
      name += tz_.next().text;
    }
    const char* what = kind == BvhNode::Kind::kRoot ? "ROOT" : "JOINT";
    if (name.empty()) fail(line, std::string(what) + " without a name");
    if (++joints_ > kMaxBvhJoints) {
      fail(line, "more than " + std::to_string(kMaxBvhJoints) + " joints (rule: kMaxBvhJoints)");
    }
    const auto [it, fresh] = names_.emplace(name, line);
    if (!fresh) {
      fail(line, "joint name '" + name + "' is already used on line " + std::to_string(it->second) +
                     " (rule: joint names are unique)");
    }
    const Token brace = tz_.next();
    if (brace.text != "{") {
      fail(brace.line, std::string("expected '{' after ") + what + " " + name + ", found " +
                           (brace.end() ? "the end of the file" : show(brace.text)));
    }
    BvhNode n;
    n.kind = kind;
    n.name = std::move(name);
    n.parent = stack_.empty() ? -1 : stack_.back().node;
    n.line = line;
    doc_.nodes.push_back(std::move(n));
    stack_.push_back({static_cast<int>(doc_.nodes.size()) - 1});
  }

  void open_end_site(int line) {
    if (iequals(tz_.peek().text, "Site") && tz_.peek().line == line) tz_.next();
    if (++end_sites_ > kMaxBvhJoints) {
      fail(line, "more than " + std::to_string(kMaxBvhJoints) +
                     " End Sites (rule: kMaxBvhJoints)");
    }
    const Token brace = tz_.next();
    if (brace.text != "{") {
      fail(brace.line, "expected '{' after End Site, found " +
                           (brace.end() ? std::string("the end of the file") : show(brace.text)));
    }
    BvhNode n;
    n.kind = BvhNode::Kind::kEndSite;
    n.parent = stack_.back().node;
    n.line = line;
    doc_.nodes.push_back(std::move(n));
    stack_.push_back({static_cast<int>(doc_.nodes.size()) - 1});
  }

  double number(const Token& t, const std::string& what) {
    double v = 0;
    if (t.end()) fail(t.line, what + ": expected a number, found the end of the file");
    switch (parse_number(t.text.data(), t.text.data() + t.text.size(), v)) {
      case NumberStatus::kNotANumber:
        fail(t.line, what + ": " + show(t.text) + " is not a number");
      case NumberStatus::kOutOfRange:
        fail(t.line, what + ": " + show(t.text) + " is out of range");
      case NumberStatus::kOk: break;
    }
    if (!std::isfinite(v)) fail(t.line, what + ": " + show(t.text) + " is not finite (NaN or inf)");
    return v;
  }

  void offset(int node) {
    Open& open = stack_.back();
    const std::string what = "OFFSET of " + describe(node);
    if (open.offset) fail(tz_.line(), describe(node) + " has a second OFFSET");
    if (open.children) fail(tz_.line(), what + " comes after its children");
    Vector3 o;
    for (int k = 0; k < 3; ++k) {
      const Token t = tz_.next();
      if (t.end() || is_keyword(t.text)) {
        fail(t.line, what + " has " + std::to_string(k) + " numbers (rule: OFFSET x y z)");
      }
      o[k] = number(t, what);
      if (std::abs(o[k]) > kMaxBvhMagnitude) {
        fail(t.line, what + ": " + show(t.text) + " exceeds " + num(kMaxBvhMagnitude) +
                         " in magnitude (rule: kMaxBvhMagnitude)");
      }
    }
    doc_.nodes[node].offset = o;
    open.offset = true;
  }

  void channels(int node, int line) {
    Open& open = stack_.back();
    if (open.channels) fail(line, describe(node) + " has a second CHANNELS");
    const Token c = tz_.next();
    int count = -1;
    if (!c.end() && c.text.size() <= 2) {
      int v = 0;
      const auto r = std::from_chars(c.text.data(), c.text.data() + c.text.size(), v);
      if (r.ec == std::errc() && r.ptr == c.text.data() + c.text.size()) count = v;
    }
    if (count < 0 || count > 6) {
      fail(c.line, "CHANNELS of " + describe(node) + ": " +
                       (c.end() ? std::string("the file ends") : show(c.text)) +
                       " is not a channel count (rule: CHANNELS n, 0 <= n <= 6, then n names)");
    }
    BvhNode& n = doc_.nodes[node];
    for (int k = 0; k < count; ++k) {
      const Token& t = tz_.peek();
      if (t.end() || is_keyword(t.text)) {
        fail(t.line, "CHANNELS of " + describe(node) + " declares " + std::to_string(count) +
                         " channels but lists " + std::to_string(k) +
                         " (rule: the count equals the channel names that follow)");
      }
      const auto ch = channel_from(t.text);
      if (!ch) {
        fail(t.line, "unknown channel " + show(t.text) + " in " + describe(node) +
                         " (rule: channels are Xposition Yposition Zposition Xrotation Yrotation "
                         "Zrotation)");
      }
      if (std::find(n.channels.begin(), n.channels.end(), *ch) != n.channels.end()) {
        fail(t.line, "channel " + std::string(to_string(*ch)) + " appears twice in " +
                         describe(node) + " (rule: each channel at most once per joint)");
      }
      n.channels.push_back(*ch);
      tz_.next();
    }
    if (channel_from(tz_.peek().text)) {
      fail(tz_.peek().line, "CHANNELS of " + describe(node) + " declares " +
                                std::to_string(count) + " channels but lists more (" +
                                show(tz_.peek().text) +
                                "; rule: the count equals the channel names that follow)");
    }
    n.first_value = doc_.channels;
    doc_.channels += count;
    open.channels = true;
  }

  // Frames: N / Frame Time: dt, then one line of values per frame
  void motion() {
    Token t = tz_.next();
    const int frames_line = t.line;
    if (iequals(t.text, "Frames")) {
      if (tz_.peek().text == ":") tz_.next();
    } else if (!iequals(t.text, "Frames:")) {
      fail(t.line, "expected 'Frames:' after MOTION, found " +
                       (t.end() ? std::string("the end of the file") : show(t.text)));
    }
    t = tz_.next();
    long long frames = -1;
    {
      const char* b = t.text.data();
      const char* e = b + t.text.size();
      if (b != e && *b == '+') ++b;
      long long v = 0;
      const auto r = std::from_chars(b, e, v);
      if (!t.end() && r.ptr == e && r.ec == std::errc() && v >= 0) frames = v;
      else if (!t.end() && r.ptr == e && r.ec == std::errc::result_out_of_range) frames = kMaxBvhFrames + 1LL;
    }
    if (frames < 0) {
      fail(t.line, "Frames: " + (t.end() ? std::string("the file ends") : show(t.text)) +
                       " is not a frame count (rule: a whole number >= 0)");
    }
    if (frames > kMaxBvhFrames) {
      fail(t.line, "Frames: " + std::string(t.text) + " exceeds the limit of " +
                       std::to_string(kMaxBvhFrames) + " frames (rule: kMaxBvhFrames)");
    }
    doc_.frames = static_cast<int>(frames);

    t = tz_.next();
    bool time_ok = iequals(t.text, "Frame") && (iequals(tz_.peek().text, "Time:") ||
                                                iequals(tz_.peek().text, "Time"));
    if (time_ok) {
      const Token time = tz_.next();
      if (iequals(time.text, "Time") && tz_.peek().text == ":") tz_.next();
    } else {
      fail(t.line, "expected 'Frame Time:' after 'Frames:', found " +
                       (t.end() ? std::string("the end of the file") : show(t.text)));
    }
    t = tz_.next();
    const double dt = number(t, "Frame Time");
    if (dt <= 0 || dt > kMaxBvhFrameTime) {
      fail(t.line, "Frame Time " + show(t.text) + " is not in (0, " + num(kMaxBvhFrameTime) +
                       "] seconds (rule: seconds per frame, > 0)");
    }
    doc_.frame_time = dt;
    const int time_line = t.line;

    // the rest of the Frame Time line must be blank; the data starts on the next line
    const char* const begin = text_.data();
    const char* const end = begin + text_.size();
    const char* p = begin + tz_.position();
    while (p < end && *p != '\n') {
      if (!is_blank(*p)) {
        const char* q = p;
        while (q < end && *q != '\n' && !is_blank(*q)) ++q;
        fail(time_line, "unexpected " + show(std::string_view(p, q - p)) +
                            " after Frame Time (rule: motion data starts on the next line)");
      }
      ++p;
    }
    if (p < end) ++p;
    values(p, end, time_line + 1, frames_line);
  }

  void values(const char* p, const char* const end, int line, int frames_line) {
    const int nch = doc_.channels;
    const int frames = doc_.frames;
    int stored = 0;
    int extra = 0;
    int extra_line = 0;
    int last = line - 1;  // the last line holding data (the Frame Time line before any)
    for (; p < end; ++line) {
      const char* eol = static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
      if (!eol) eol = end;
      if (static_cast<size_t>(eol - p) > kMaxBvhLineBytes) {
        fail(line, "the line is longer than " + std::to_string(kMaxBvhLineBytes) +
                       " bytes (rule: kMaxBvhLineBytes)");
      }
      const char* s = p;
      while (s < eol && is_blank(*s)) ++s;
      // a blank line is skipped, except that it is a frame of a skeleton without channels
      if (s == eol && !(nch == 0 && stored < frames && eol < end)) {
        p = eol + (eol < end ? 1 : 0);
        if (eol == end) break;
        continue;
      }
      last = line;
      double* out = nullptr;
      const bool frame_line = stored < frames;
      if (frame_line) {
        if (nch > 0) {
          if (doc_.values.capacity() == 0) {
            // reserve what this line's length says the remaining bytes can hold, never more
            // than the header claims: a lying header cannot make the parser allocate
            const size_t len = static_cast<size_t>(eol - p) + 1;
            const size_t fit = static_cast<size_t>(end - p) / len + 1;
            doc_.values.reserve(std::min(static_cast<size_t>(frames), fit) * nch);
          }
          const size_t at = doc_.values.size();
          doc_.values.resize(at + nch);
          out = doc_.values.data() + at;
        }
      } else if (++extra > 1) {
        fail(line, "motion data goes on past the " + std::to_string(frames) +
                       " frames that 'Frames:' declares on line " + std::to_string(frames_line) +
                       " (rule: one line per frame; a single extra line is tolerated)");
      } else {
        extra_line = line;
      }
      const int count = motion_line(s, eol, out, nch, line, stored);
      if (count != nch) {
        fail(line, "frame " + std::to_string(stored + 1) + " has " + std::to_string(count) +
                       " values, expected " + std::to_string(nch) +
                       " (rule: one value per channel of the hierarchy on every motion line)");
      }
      if (frame_line) ++stored;
      p = eol + (eol < end ? 1 : 0);
      if (eol == end) break;
    }
    if (stored < frames) {
      fail(last, "'Frames:' on line " + std::to_string(frames_line) + " declares " +
                     std::to_string(frames) + " frames but the file holds " +
                     std::to_string(stored) + " motion lines, the last on line " +
                     std::to_string(last) +
                     " (rule: Frames is the number of motion lines; truncated file?)");
    }
    if (nch == 0) doc_.values.clear();
    if (extra == 1) {
      doc_.warnings.push_back(source_ + ": line " + std::to_string(extra_line) +
                              ": one motion line beyond the " + std::to_string(frames) +
                              " frames declared on line " + std::to_string(frames_line) +
                              " is ignored");
    }
  }

  // parses the values of one line into out (when given); returns how many there are
  int motion_line(const char* p, const char* eol, double* out, int nch, int line, int frame) {
    int count = 0;
    while (true) {
      while (p < eol && is_blank(*p)) ++p;
      if (p == eol) break;
      const char* b = p;
      while (p < eol && !is_blank(*p)) ++p;
      double v = 0;
      const NumberStatus st = parse_number(b, p, v);
      const std::string_view tok(b, static_cast<size_t>(p - b));
      if (st != NumberStatus::kOk || !std::isfinite(v) || std::abs(v) > kMaxBvhMagnitude) {
        const std::string where = "frame " + std::to_string(frame + 1) + ", value " +
                                  std::to_string(count + 1) + ": " + show(tok);
        if (st == NumberStatus::kNotANumber) fail(line, where + " is not a number");
        if (st == NumberStatus::kOutOfRange) fail(line, where + " is out of range");
        if (!std::isfinite(v)) fail(line, where + " is not finite (NaN or inf)");
        fail(line, where + " exceeds " + num(kMaxBvhMagnitude) +
                       " in magnitude (rule: kMaxBvhMagnitude)");
      }
      if (out && count < nch) out[count] = v;
      ++count;
    }
    return count;
  }

  std::string_view text_;
  const std::string& source_;
  Tokenizer tz_;
  BvhDocument doc_;
  std::vector<Open> stack_;
  std::unordered_map<std::string, int> names_;
  int joints_ = 0;
  int end_sites_ = 0;
};

// ---------------------------------------------------------------------------------------------
// rotations

Quaternion elementary_quaternion(int axis, double radians) {
  const double h = 0.5 * radians;
  Quaternion q(std::cos(h), 0, 0, 0);
  q.coeffs()[axis] = std::sin(h);  // coeffs() is (x, y, z, w)
  return q;
}

Matrix3 elementary_matrix(int axis, double radians) {
  const double c = std::cos(radians), s = std::sin(radians);
  Matrix3 R = Matrix3::Identity();
  const int a = (axis + 1) % 3, b = (axis + 2) % 3;
  R(a, a) = c;
  R(a, b) = -s;
  R(b, a) = s;
  R(b, b) = c;
  return R;
}

Quaternion joint_quaternion(const BvhNode& node, const double* v) {
  Quaternion q = Quaternion::Identity();
  for (size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (is_rotation(c)) q = q * elementary_quaternion(channel_axis(c), v[k] * kDegree);
  }
  return q.normalized();
}

// local translation: OFFSET with the components that have position channels replaced
Vector3 joint_translation(const BvhNode& node, const double* v) {
  Vector3 p = node.offset;
  for (size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (!is_rotation(c)) p[channel_axis(c)] = v[k];
  }
  return p;
}

bool has_position(const BvhNode& n) {
  return std::any_of(n.channels.begin(), n.channels.end(),
                     [](BvhChannel c) { return !is_rotation(c); });
}

double wrap_near(double angle, double reference) {
  const double two_pi = 2 * std::numbers::pi;
  return angle + two_pi * std::round((reference - angle) / two_pi);
}

// the rotation order of a layout joint: its rotation channels, missing axes appended X, Y, Z
BvhRotationOrder order_of(const std::vector<BvhChannel>& channels) {
  BvhRotationOrder order{};
  int n = 0;
  bool used[3] = {false, false, false};
  for (BvhChannel c : channels) {
    if (is_rotation(c) && !used[channel_axis(c)] && n < 3) {
      used[channel_axis(c)] = true;
      order[n++] = channel_axis(c);
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!used[a]) order[n++] = a;
  }
  return order;
}

// The rotation of the shortest arc from +Z to the direction of d (d != 0, finite): the unit
// quaternion proportional to (1 + u_z, z × u) with u = d / |d|. Near -Z, 1 + u_z is taken as
// (u_x² + u_y²) / (1 - u_z), free of cancellation; Eigen's FromTwoVectors loses it there and
// returns quaternions up to 1e-6 off unit length, whose matrices the model builder refuses as not
// orthonormal. Both vectors are scaled by their largest component first, so neither a 1e9 nor a
// denormal component under- or overflows. Exactly -Z: a half turn about X.
Matrix3 rotation_from_z(const Vector3& d) {
  const Vector3 a = d / d.cwiseAbs().maxCoeff();
  const Vector3 u = a / a.norm();  // |a| in [1, √3]
  const double w = u.z() >= 0 ? 1 + u.z() : (u.x() * u.x() + u.y() * u.y()) / (1 - u.z());
  Quaternion q(w, -u.y(), u.x(), 0);
  const double largest = q.coeffs().cwiseAbs().maxCoeff();
  if (!(largest > 0)) return Quaternion(0, 1, 0, 0).toRotationMatrix();
  q.coeffs() /= largest;
  q.normalize();
  return q.toRotationMatrix();
}

}  // namespace

// -----------------------------------------------------------------------------------------------

const char* to_string(BvhChannel c) {
  switch (c) {
    case BvhChannel::kXposition: return "Xposition";
    case BvhChannel::kYposition: return "Yposition";
    case BvhChannel::kZposition: return "Zposition";
    case BvhChannel::kXrotation: return "Xrotation";
    case BvhChannel::kYrotation: return "Yrotation";
    case BvhChannel::kZrotation: return "Zrotation";
  }
  return "?";
}

std::optional<BvhRotationOrder> parse_rotation_order(std::string_view s) {
  if (s.size() != 3) return std::nullopt;
  BvhRotationOrder order{};
  bool used[3] = {false, false, false};
  for (int k = 0; k < 3; ++k) {
    const char c = lower(s[k]);
    if (c < 'x' || c > 'z') return std::nullopt;
    const int a = c - 'x';
    if (used[a]) return std::nullopt;
    used[a] = true;
    order[k] = a;
  }
  return order;
}

std::string to_string(const BvhRotationOrder& order) {
  std::string s;
  for (int a : order) s += static_cast<char>('X' + a);
  return s;
}

Matrix3 euler_to_matrix(const BvhRotationOrder& order, const Vector3& angles) {
  return elementary_matrix(order[0], angles[0]) * elementary_matrix(order[1], angles[1]) *
         elementary_matrix(order[2], angles[2]);
}

Vector3 matrix_to_euler(const Matrix3& R, const BvhRotationOrder& order, const Vector3* previous) {
  const int i = order[0], j = order[1], k = order[2];
  // parity of the permutation (i, j, k): +1 for XYZ, YZX, ZXY
  const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
  // R = R_i(a) R_j(b) R_k(c): R(i, k) = s sin b, and the other entries of row i and column k
  // carry cos b (see ecosystem.md §1.3 for ZXY)
  const double cos_b = std::hypot(R(i, i), R(i, j));
  const double b = std::atan2(s * R(i, k), cos_b);
  double a = 0;
  if (std::hypot(R(j, k), R(k, k)) > 1e-12) {
    a = std::atan2(-s * R(j, k), R(k, k));
  } else if (previous) {
    a = (*previous)[0];  // gimbal lock: only a ± c is defined; keep a continuous
  }
  // c from what is left: R_k(c) = R_j(b)ᵀ R_i(a)ᵀ R, exact even near the singularity
  const Matrix3 M = (elementary_matrix(i, a) * elementary_matrix(j, b)).transpose() * R;
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  const double c = std::atan2(M(k2, k1), M(k1, k1));
  Vector3 first(a, b, c);
  if (!previous) return first;
  // the equivalent triple (a + π, π - b, c + π); each unwrapped to the previous frame
  const double pi = std::numbers::pi;
  Vector3 second(a + pi, pi - b, c + pi);
  for (int n = 0; n < 3; ++n) {
    first[n] = wrap_near(first[n], (*previous)[n]);
    second[n] = wrap_near(second[n], (*previous)[n]);
  }
  return (first - *previous).cwiseAbs().sum() <= (second - *previous).cwiseAbs().sum() ? first
                                                                                       : second;
}

int BvhDocument::joint_count() const {
  return static_cast<int>(std::count_if(nodes.begin(), nodes.end(),
                                        [](const BvhNode& n) { return !n.is_end_site(); }));
}

BvhDocument parse_bvh(std::string_view text, const std::string& source_name) {
  return Parser(text, source_name).parse();
}

Matrix3 bvh_joint_rotation(const BvhNode& node, const double* frame_values) {
  Matrix3 R = Matrix3::Identity();
  for (size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (is_rotation(c)) R = R * elementary_matrix(channel_axis(c), frame_values[k] * kDegree);
  }
  return R;
}

std::vector<Transform> bvh_world_poses(const BvhDocument& doc, int frame) {
  std::vector<Transform> X(doc.nodes.size());
  const double* values = frame >= 0 ? doc.frame(frame) : nullptr;
  for (size_t n = 0; n < doc.nodes.size(); ++n) {
    const BvhNode& node = doc.nodes[n];
    Transform local = Transform::from_translation(node.offset);
    if (values && !node.is_end_site()) {
      const double* v = values + node.first_value;
      local.p = joint_translation(node, v);
      local.R = bvh_joint_rotation(node, v);
    }
    X[n] = node.parent < 0 ? local : X[node.parent] * local;
  }
  return X;
}

BvhExtent bvh_rest_extent(const BvhDocument& doc) {
  if (doc.nodes.empty()) return {};
  const std::vector<Transform> X = bvh_world_poses(doc, -1);
  Vector3 lo = X[0].p, hi = X[0].p;
  for (const Transform& x : X) {
    lo = lo.cwiseMin(x.p);
    hi = hi.cwiseMax(x.p);
  }
  const Vector3 size = hi - lo;
  return {size.y(), size.maxCoeff()};
}

BvhUnit bvh_auto_scale(const BvhDocument& doc) {
  const double size = bvh_rest_extent(doc).largest;
  if (!(size > 0) || !std::isfinite(size)) return {1.0, "metres (the skeleton has no extent)"};
  struct Candidate {
    double scale;
    const char* unit;
  };
  static constexpr Candidate kUnits[] = {{1.0, "metres"},
                                         {0.01, "centimetres"},
                                         {0.001, "millimetres"},
                                         {0.0254, "inches"},
                                         {kCmuUnit, "CMU units (1/0.45 inch)"}};
  constexpr double kTypical = 1.7;  // metres, a standing adult or an arm span
  BvhUnit best{1.0, ""};
  double best_error = kInfinity;
  for (const Candidate& c : kUnits) {
    const double error = std::abs(std::log(size * c.scale / kTypical));
    if (error < best_error) {
      best_error = error;
      best = {c.scale, c.unit};
    }
  }
  return best;
}

const BvhLayout::Joint* BvhLayout::find(std::string_view name) const {
  for (const Joint& j : joints) {
    if (j.name == name) return &j;
  }
  return nullptr;
}

// -----------------------------------------------------------------------------------------------
// import

BvhImport import_bvh(const BvhDocument& doc, const std::string& source_name,
                     const BvhImportOptions& options) {
  auto fail = [&](const std::string& what) { throw ModelError({source_name + ": " + what}); };
  if (doc.nodes.empty()) fail("the hierarchy has no joints");
  if (!std::isfinite(options.total_mass) || options.total_mass <= 0) {
    fail("total mass " + num(options.total_mass) + " is not a positive finite number");
  }
  BvhImport out;
  double s = 1.0;
  if (options.scale) {
    s = *options.scale;
    if (!std::isfinite(s) || s <= 0) {
      fail("scale " + num(s) + " is not a positive finite number (metres per file unit)");
    }
    out.unit = "option";
  } else {
    const BvhUnit u = bvh_auto_scale(doc);
    s = u.scale;
    out.unit = u.unit;
  }
  const BvhExtent extent = bvh_rest_extent(doc);
  out.height = extent.height * s;
  // size of the figure for capsule radii; 1 m when the skeleton has no extent (under 1 µm, where
  // radii squared would underflow into links of mass without inertia)
  constexpr double kNoExtent = 1e-6;  // metres
  const double h = extent.largest * s > kNoExtent ? extent.largest * s : 1.0;

  // link names: the joint names, End Sites "<joint>_end" made unique
  const int n = static_cast<int>(doc.nodes.size());
  std::vector<std::string> link_name(n);
  std::unordered_set<std::string> used;
  for (int i = 0; i < n; ++i) {
    if (!doc.nodes[i].is_end_site()) used.insert(doc.nodes[i].name);
  }
  for (int i = 0; i < n; ++i) {
    const BvhNode& node = doc.nodes[i];
    if (!node.is_end_site()) {
      link_name[i] = node.name;
      continue;
    }
    const std::string base = doc.nodes[node.parent].name + "_end";
    std::string name = base;
    for (int k = 2; used.count(name); ++k) name = base + "_" + std::to_string(k);
    used.insert(name);
    link_name[i] = name;
  }

  // bones: from each joint to its children; mass in proportion to their length
  std::vector<std::vector<Vector3>> bones(n);
  for (int i = 1; i < n; ++i) bones[doc.nodes[i].parent].push_back(doc.nodes[i].offset * s);
  std::vector<double> weight(n, 0.0);
  double total_weight = 0;
  for (int i = 0; i < n; ++i) {
    if (doc.nodes[i].is_end_site()) continue;
    double length = 0;
    for (const Vector3& d : bones[i]) length += d.norm();
    weight[i] = std::max(length, 0.02 * h);
    total_weight += weight[i];
  }

  ModelBuilder builder(std::filesystem::path(source_name).stem().string());
  for (int i = 0; i < n; ++i) {
    const BvhNode& node = doc.nodes[i];
    LinkSpec l;
    l.name = link_name[i];
    l.parent = node.parent < 0 ? "" : link_name[node.parent];
    l.joint.X_PJ = Transform::from_translation(node.offset * s);
    if (node.is_end_site()) {
      l.joint.type = JointType::kFixed;
    } else if (node.parent < 0 || has_position(node)) {
      l.joint.type = JointType::kFree;
    } else {
      l.joint.type = JointType::kSpherical;  // also with fewer than 3 rotation channels, or none
    }
    if (!node.is_end_site()) {
      // each bone a capsule: a solid cylinder for the inertia, a capsule for collisions
      l.mass = options.total_mass * weight[i] / total_weight;
      double length = 0;
      for (const Vector3& d : bones[i]) length += d.norm();
      const double tiny = 1e-9 * h;
      if (length <= tiny) {
        const double r = 0.02 * h;
        l.I_com = Matrix3::Identity() * (0.4 * l.mass * r * r);
        Geometry g;
        g.shape = Geometry::Shape::kSphere;
        g.radius = r;
        l.collision.push_back(g);
      } else {
        std::vector<double> mb;
        std::vector<Vector3> cb;
        std::vector<Matrix3> Ib;
        for (const Vector3& d : bones[i]) {
          const double L = d.norm();
          if (L <= tiny) continue;
          const double m = l.mass * L / length;
          const double r = std::clamp(0.12 * L, 0.01 * h, 0.05 * h);
          const Vector3 u = d / L;
          const double axial = 0.5 * m * r * r;
          const double perp = m * (3 * r * r + L * L) / 12.0;
          mb.push_back(m);
          cb.push_back(0.5 * d);
          Ib.push_back(perp * Matrix3::Identity() + (axial - perp) * u * u.transpose());
          Geometry g;
          g.shape = Geometry::Shape::kCapsule;
          g.radius = r;
          g.length = L;
          g.X_LinkShape = {rotation_from_z(d), 0.5 * d};
          l.collision.push_back(g);
        }
        Vector3 com = Vector3::Zero();
        for (size_t k = 0; k < mb.size(); ++k) com += mb[k] * cb[k];
        com /= l.mass;
        Matrix3 I = Matrix3::Zero();
        for (size_t k = 0; k < mb.size(); ++k) {
          const Vector3 e = cb[k] - com;
          I += Ib[k] + mb[k] * (e.squaredNorm() * Matrix3::Identity() - e * e.transpose());
        }
        l.com = com;
        l.I_com = 0.5 * (I + I.transpose());
      }
    }
    builder.add_link(std::move(l));
  }
  try {
    out.model = builder.finalize();
  } catch (const ModelError& e) {
    std::vector<std::string> v;
    for (const std::string& line : e.violations()) v.push_back(source_name + ": " + line);
    throw ModelError(v);
  }
  const Model& m = *out.model;

  // the clip: one configuration per frame
  struct JointMap {
    const BvhNode* node;
    int iq;
    JointType type;
  };
  std::vector<JointMap> joints;
  out.node_link.assign(n, -1);
  for (int i = 0; i < n; ++i) {
    const int link = m.link_index(link_name[i]);
    out.node_link[i] = link;
    const BvhNode& node = doc.nodes[i];
    if (node.is_end_site()) continue;
    out.layout.joints.push_back({node.name, node.channels});
    if (m.joint_type[link] == JointType::kFixed) continue;
    joints.push_back({&node, m.idx_q[link], m.joint_type[link]});
  }
  out.layout.scale = s;
  out.clip.frame_time = doc.frame_time;
  out.clip.frames.reserve(static_cast<size_t>(doc.frames));
  const Eigen::VectorXd neutral = neutral_configuration(m);
  const int step = std::max(1, doc.frames / 50);
  for (int f = 0; f < doc.frames; ++f) {
    Eigen::VectorXd q = neutral;
    const double* values = doc.frame(f);
    const Eigen::VectorXd* prev = f > 0 ? &out.clip.frames.back() : nullptr;
    for (const JointMap& j : joints) {
      const double* v = values + j.node->first_value;
      const int iq_rot = j.type == JointType::kFree ? j.iq + 3 : j.iq;
      Quaternion r = joint_quaternion(*j.node, v);
      // keep the quaternion on the previous frame's hemisphere
      if (prev && quaternion_at(*prev, iq_rot).coeffs().dot(r.coeffs()) < 0) r.coeffs() *= -1;
      set_quaternion_at(q, iq_rot, r);
      if (j.type == JointType::kFree) {
        q.segment<3>(j.iq) = (joint_translation(*j.node, v) - j.node->offset) * s;
      }
    }
    out.clip.frames.push_back(std::move(q));
    if (options.progress && f % step == 0) options.progress(static_cast<double>(f) / doc.frames);
  }
  if (options.progress) options.progress(1.0);
  out.warnings = doc.warnings;
  return out;
}

BvhImport load_bvh_string(std::string_view text, const std::string& source_name,
                          const BvhImportOptions& options) {
  if (text.size() > kMaxBvhBytes) {
    throw ModelError({source_name + ": " + std::to_string(text.size()) + " bytes (rule: at most " +
                      std::to_string(kMaxBvhBytes) + " bytes, kMaxBvhBytes)"});
  }
  return import_bvh(parse_bvh(text, source_name), source_name, options);
}

BvhImport load_bvh_file(const std::string& path, const BvhImportOptions& options) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    throw ModelError({path + ": cannot open the file" + (ec ? ": " + ec.message() : "")});
  }
  if (!fs::is_regular_file(st)) {
    throw ModelError({path + ": not a regular file (rule: a BVH file is a plain file)"});
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw ModelError({path + ": cannot read the file size: " + ec.message()});
  if (size > kMaxBvhBytes) {
    throw ModelError({path + ": the file is " + std::to_string(size) + " bytes (rule: at most " +
                      std::to_string(kMaxBvhBytes) + " bytes, kMaxBvhBytes)"});
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ModelError({path + ": cannot open the file"});
  std::string text(static_cast<size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  text.resize(static_cast<size_t>(in.gcount()));
  if (in.bad()) throw ModelError({path + ": read error"});
  return load_bvh_string(text, path, options);
}

// -----------------------------------------------------------------------------------------------
// export

std::string sanitize_bvh_name(std::string_view name) {
  std::string s(name);
  for (char& c : s) {
    const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                    c == '_';
    if (!ok) c = '_';
  }
  return s.empty() ? "joint" : s;
}

BvhDocument make_bvh_document(const Model& model, const Clip& clip,
                              const BvhExportOptions& options) {
  if (model.njoints < 2) throw std::invalid_argument("BVH export: the model has no links");
  if (const std::string e = check_clip(model, clip); !e.empty()) {
    throw std::invalid_argument("BVH export: the clip does not fit model '" + model.name +
                                "': " + e);
  }
  std::optional<BvhRotationOrder> forced;
  if (options.rotation_order) {
    forced = parse_rotation_order(*options.rotation_order);
    if (!forced) {
      throw std::invalid_argument("BVH export: rotation order '" + *options.rotation_order +
                                  "' is not a permutation of XYZ");
    }
  }
  const double s = options.scale ? *options.scale : options.layout ? options.layout->scale : 1.0;
  if (!std::isfinite(s) || s <= 0) {
    throw std::invalid_argument("BVH export: scale " + num(s) +
                                " is not a positive finite number (metres per file unit)");
  }
  const BvhRotationOrder zxy{2, 0, 1};
  const int nj = model.njoints;

  // which links move something below them (fixed links with none become End Sites)
  std::vector<char> moving(nj, 0);
  for (int i = nj - 1; i >= 1; --i) {
    if (model.joint_type[i] != JointType::kFixed) moving[i] = 1;
    if (model.parent[i] > 0 && moving[i]) moving[model.parent[i]] = 1;
  }

  // the written nodes, in the model's depth-first order (a valid BVH pre-order)
  struct Written {
    int link = -1;           // model link (-1 for an added End Site)
    Transform pre;           // constant transform from the written parent to the joint's parent
    BvhRotationOrder order{};
    bool position = false;   // writes position channels
  };
  BvhDocument doc;
  std::vector<Written> written;
  std::vector<int> anchor(nj, -1);                          // written node a link hangs from
  std::vector<Transform> C(nj, Transform::Identity());     // that node's frame → the link frame
  for (int i = 1; i < nj; ++i) {
    const int p = model.parent[i];
    BvhNode node;
    Written w;
    w.link = i;
    const bool root = p == 0;
    const int a = root ? -1 : anchor[p];
    const Transform Cp = root ? Transform::Identity() : C[p];
    if (!root && model.joint_type[i] == JointType::kFixed) {
      const Transform T = Cp * model.X_PJ[i];
      const bool leaf = model.subtree_end[i] == i + 1;
      if (moving[i] || !leaf) {  // fold into the written parent
        anchor[i] = a;
        C[i] = T;
        continue;
      }
      node.kind = BvhNode::Kind::kEndSite;
      node.parent = a;
      node.offset = T.p / s;
    } else {
      const JointType t = model.joint_type[i];
      const BvhLayout::Joint* lj = options.layout ? options.layout->find(model.link_name[i]) : nullptr;
      w.order = forced ? *forced : lj ? order_of(lj->channels) : zxy;
      w.position = root || t == JointType::kFree || t == JointType::kPrismatic;
      w.pre = Cp;
      node.kind = root ? BvhNode::Kind::kRoot : BvhNode::Kind::kJoint;
      node.name = model.link_name[i];
      node.parent = a;
      // a joint that only rotates keeps its origin: the constant OFFSET; one that translates
      // carries its whole translation in position channels over OFFSET 0 0 0
      node.offset = w.position ? Vector3::Zero() : Vector3((Cp * model.X_PJ[i]).p / s);
      if (w.position) {
        node.channels = {BvhChannel::kXposition, BvhChannel::kYposition, BvhChannel::kZposition};
      }
      for (int axis : w.order) {
        node.channels.push_back(static_cast<BvhChannel>(static_cast<int>(BvhChannel::kXrotation) + axis));
      }
      anchor[i] = static_cast<int>(doc.nodes.size());
      C[i] = Transform::Identity();
    }
    doc.nodes.push_back(std::move(node));
    written.push_back(w);
  }

  // a leaf joint gets an End Site at its origin, unless it comes from an imported file as it is
  {
    std::vector<int> nchildren(doc.nodes.size(), 0);
    for (const BvhNode& node : doc.nodes) {
      if (node.parent >= 0) ++nchildren[node.parent];
    }
    std::vector<BvhNode> nodes;
    std::vector<Written> ws;
    std::vector<int> remap(doc.nodes.size(), -1);
    for (size_t k = 0; k < doc.nodes.size(); ++k) {
      BvhNode node = std::move(doc.nodes[k]);
      if (node.parent >= 0) node.parent = remap[node.parent];
      remap[k] = static_cast<int>(nodes.size());
      const bool add_end = !node.is_end_site() && nchildren[k] == 0 &&
                           !(options.layout && options.layout->find(node.name));
      nodes.push_back(std::move(node));
      ws.push_back(written[k]);
      if (add_end) {
        BvhNode e;
        e.kind = BvhNode::Kind::kEndSite;
        e.parent = remap[k];
        nodes.push_back(std::move(e));
        ws.push_back(Written{});
      }
    }
    doc.nodes = std::move(nodes);
    written = std::move(ws);
  }
  for (BvhNode& node : doc.nodes) {
    node.first_value = doc.channels;
    doc.channels += static_cast<int>(node.channels.size());
  }

  // values: each joint's pose relative to its written parent, as Euler angles unwrapped across
  // frames
  doc.frames = clip.size();
  doc.frame_time = clip.frame_time;
  doc.values.resize(static_cast<size_t>(doc.frames) * doc.channels);
  Data data(model);
  std::vector<Vector3> previous(doc.nodes.size(), Vector3::Zero());
  const int step = std::max(1, doc.frames / 50);
  for (int f = 0; f < doc.frames; ++f) {
    forward_kinematics(model, data, clip.frames[f]);
    double* row = doc.values.data() + static_cast<size_t>(f) * doc.channels;
    for (size_t k = 0; k < doc.nodes.size(); ++k) {
      const BvhNode& node = doc.nodes[k];
      if (node.is_end_site()) continue;
      const Written& w = written[k];
      const Transform X = w.pre * data.X_P[w.link];
      double* v = row + node.first_value;
      if (w.position) {
        for (int c = 0; c < 3; ++c) *v++ = X.p[c] / s;
      }
      const Vector3 angles = matrix_to_euler(X.R, w.order, f > 0 ? &previous[k] : nullptr);
      previous[k] = angles;
      for (int c = 0; c < 3; ++c) *v++ = angles[c] / kDegree;
    }
    if (options.progress && f % step == 0) options.progress(static_cast<double>(f) / doc.frames);
  }
  if (options.progress) options.progress(1.0);
  return doc;
}

std::string format_bvh(const BvhDocument& doc) {
  const size_t n = doc.nodes.size();
  if (n == 0 || doc.nodes[0].kind != BvhNode::Kind::kRoot) {
    throw std::invalid_argument("BVH writer: the document does not start with its ROOT");
  }
  if (doc.frames < 0 || doc.values.size() != static_cast<size_t>(doc.frames) * doc.channels) {
    throw std::invalid_argument("BVH writer: " + std::to_string(doc.values.size()) +
                                " values do not fill " + std::to_string(doc.frames) + " frames of " +
                                std::to_string(doc.channels) + " channels");
  }
  if (!std::isfinite(doc.frame_time) || doc.frame_time <= 0 ||
      doc.frame_time > kMaxBvhFrameTime) {
    throw std::invalid_argument("BVH writer: frame time " + num(doc.frame_time) +
                                " is not in (0, kMaxBvhFrameTime]");
  }
  if (doc.frames > kMaxBvhFrames) {
    throw std::invalid_argument("BVH writer: " + std::to_string(doc.frames) +
                                " frames exceed kMaxBvhFrames");
  }
  const int joints = doc.joint_count();
  if (joints > kMaxBvhJoints || static_cast<int>(n) - joints > kMaxBvhJoints) {
    throw std::invalid_argument("BVH writer: more joints or End Sites than kMaxBvhJoints");
  }
  // every number within what the reader accepts
  auto check_value = [](double v, const std::string& where) {
    if (!std::isfinite(v) || std::abs(v) > kMaxBvhMagnitude) {
      throw std::invalid_argument("BVH writer: " + where + " = " + num(v) +
                                  " is not finite or exceeds kMaxBvhMagnitude");
    }
  };
  for (size_t k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) check_value(doc.nodes[k].offset[c], "an OFFSET");
    if (doc.nodes[k].name.size() > 4096) {
      throw std::invalid_argument("BVH writer: a joint name is longer than 4096 bytes");
    }
  }
  for (size_t k = 0; k < doc.values.size(); ++k) {
    if (!(std::abs(doc.values[k]) <= kMaxBvhMagnitude)) {
      check_value(doc.values[k], "value " + std::to_string(k % std::max(1, doc.channels) + 1) +
                                     " of frame " +
                                     std::to_string(k / std::max(1, doc.channels) + 1));
    }
  }
  // names: sanitized and unique
  std::vector<std::string> names(n);
  std::unordered_set<std::string> used;
  for (size_t k = 0; k < n; ++k) {
    if (doc.nodes[k].is_end_site()) continue;
    const std::string base = sanitize_bvh_name(doc.nodes[k].name);
    std::string name = base;
    for (int i = 2; used.count(name); ++i) name = base + "_" + std::to_string(i);
    used.insert(name);
    names[k] = name;
  }

  std::string out;
  out.reserve(n * 96 + doc.values.size() * 12 + 64);
  char buf[512];
  auto put = [&](double v) {
    out.append(buf, put_fixed(buf, v));
  };
  out += "HIERARCHY\n";
  std::vector<int> open;  // stack of open nodes
  int channels = 0;
  for (size_t k = 0; k < n; ++k) {
    const BvhNode& node = doc.nodes[k];
    if (k > 0 && node.kind == BvhNode::Kind::kRoot) {
      throw std::invalid_argument("BVH writer: more than one ROOT");
    }
    while (!open.empty() && open.back() != node.parent) {
      open.pop_back();
      out.append(open.size(), '\t');
      out += "}\n";
    }
    if (open.empty() && k > 0) {
      throw std::invalid_argument("BVH writer: nodes are not in depth-first order");
    }
    if (node.first_value != channels || (node.is_end_site() && !node.channels.empty())) {
      throw std::invalid_argument("BVH writer: the channel layout of node " + std::to_string(k) +
                                  " is inconsistent");
    }
    channels += static_cast<int>(node.channels.size());
    const std::string indent(open.size(), '\t');
    out += indent;
    if (node.kind == BvhNode::Kind::kRoot) out += "ROOT " + names[k] + "\n";
    else if (node.kind == BvhNode::Kind::kJoint) out += "JOINT " + names[k] + "\n";
    else out += "End Site\n";
    out += indent + "{\n";
    out += indent + "\tOFFSET ";
    for (int c = 0; c < 3; ++c) {
      if (c) out += ' ';
      put(node.offset[c]);
    }
    out += '\n';
    if (!node.is_end_site()) {
      out += indent + "\tCHANNELS " + std::to_string(node.channels.size());
      for (BvhChannel c : node.channels) {
        out += ' ';
        out += to_string(c);
      }
      out += '\n';
    }
    open.push_back(static_cast<int>(k));
  }
  while (!open.empty()) {
    open.pop_back();
    out.append(open.size(), '\t');
    out += "}\n";
  }
  if (channels != doc.channels) {
    throw std::invalid_argument("BVH writer: the nodes hold " + std::to_string(channels) +
                                " channels, the document says " + std::to_string(doc.channels));
  }
  out += "MOTION\nFrames: " + std::to_string(doc.frames) + "\n";
  out += "Frame Time: " + frame_time_text(doc.frame_time) + "\n";
  for (int f = 0; f < doc.frames; ++f) {
    const double* v = doc.frame(f);
    for (int c = 0; c < doc.channels; ++c) {
      if (c) out += ' ';
      put(v[c]);
    }
    out += '\n';
  }
  return out;
}

std::string write_bvh(const Model& model, const Clip& clip, const BvhExportOptions& options) {
  return format_bvh(make_bvh_document(model, clip, options));
}

void save_bvh_file(const Model& model, const Clip& clip, const std::string& path,
                   const BvhExportOptions& options) {
  write_file_atomically(path, write_bvh(model, clip, options));
}

}  // namespace io
