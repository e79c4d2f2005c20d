#include "io/bvh_parser.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <optional>
#include <unordered_map>
#include <vector>

#include "io/bvh_text.hpp"
#include "io/bvh_tokenizer.hpp"

namespace io {

namespace {

using namespace bvh_detail;

std::optional<BvhChannel> channel_from(std::string_view s) {
  static constexpr std::array<const char*, 6> kNames = {"xposition", "yposition", "zposition",
                                                        "xrotation", "yrotation", "zrotation"};
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (iequals(s, kNames[i])) return static_cast<BvhChannel>(i);
  }
  return std::nullopt;
}

bool is_keyword(std::string_view s) {
  for (const char* k :
       {"ROOT", "JOINT", "End", "OFFSET", "CHANNELS", "MOTION", "HIERARCHY", "{", "}"}) {
    if (iequals(s, k)) return true;
  }
  return false;
}

// One pass: the hierarchy token by token with a stack of open nodes, the MOTION header, then the
// motion lines, read straight from the text (they hold nearly all of its bytes).
class Parser {
 public:
  Parser(std::string_view text, const std::string& source, const ClipBudget& budget)
      : text_(text), source_(source), budget_(budget), tz_(text, source) {}

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
          fail(t.line,
               show(t.text) + " inside " + describe(node) + " (rule: an End Site has no children)");
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
      fail(line, "more than " + std::to_string(kMaxBvhJoints) + " End Sites (rule: kMaxBvhJoints)");
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
      case NumberStatus::kOk:
        break;
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
      fail(tz_.peek().line, "CHANNELS of " + describe(node) + " declares " + std::to_string(count) +
                                " channels but lists more (" + show(tz_.peek().text) +
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
      if (!t.end() && r.ptr == e && r.ec == std::errc() && v >= 0)
        frames = v;
      else if (!t.end() && r.ptr == e && r.ec == std::errc::result_out_of_range)
        frames = kMaxBvhFrames + 1LL;
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
    bool time_ok = iequals(t.text, "Frame") &&
                   (iequals(tz_.peek().text, "Time:") || iequals(tz_.peek().text, "Time"));
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
    // the budget, before a single frame is stored
    if (const std::string why = clip_budget_refusal(budget_, frames, dt, numbers_per_frame());
        !why.empty()) {
      fail(frames_line,
           "Frames: " + std::to_string(frames) + " at Frame Time " + num(dt) + " s: " + why);
    }

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
      const char* eol =
          static_cast<const char*>(std::memchr(p, '\n', static_cast<size_t>(end - p)));
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

  // numbers one frame costs: the file's values, or the imported configuration when that is
  // larger (a free joint for the ROOT and for joints with position channels, a quaternion for
  // every other joint; io/bvh_import.hpp)
  std::int64_t numbers_per_frame() const {
    std::int64_t coordinates = 0;
    for (const BvhNode& n : doc_.nodes) {
      if (n.is_end_site()) continue;
      const bool moves = n.kind == BvhNode::Kind::kRoot ||
                         std::any_of(n.channels.begin(), n.channels.end(),
                                     [](BvhChannel c) { return !is_rotation(c); });
      coordinates += moves ? 7 : 4;
    }
    return std::max<std::int64_t>(doc_.channels, coordinates);
  }

  std::string_view text_;
  const std::string& source_;
  const ClipBudget& budget_;
  Tokenizer tz_;
  BvhDocument doc_;
  std::vector<Open> stack_;
  std::unordered_map<std::string, int> names_;
  int joints_ = 0;
  int end_sites_ = 0;
};

}  // namespace

BvhDocument parse_bvh(std::string_view text,
                      const std::string& source_name,
                      const ClipBudget& budget) {
  return Parser(text, source_name, budget).parse();
}

}  // namespace io
