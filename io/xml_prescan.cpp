#include "io/xml_prescan.hpp"

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <utility>

namespace io {

namespace {

// returned where TinyXML 1 would stop with an error (the scan stops with it)
constexpr std::size_t kStop = std::string_view::npos;

// TinyXML 1 reads characters with the C library's classification, and every byte from 127 up as a
// letter (TiXmlBase::IsWhiteSpace, IsAlpha, IsAlphaNum, ReadName)
bool is_space(char c) {
  return std::isspace(static_cast<unsigned char>(c)) || c == '\n' || c == '\r';
}
bool is_name_start(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u >= 127 || std::isalpha(u) || c == '_';
}
bool is_name_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u >= 127 || std::isalnum(u) || c == '_' || c == '-' || c == '.' || c == ':';
}
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_hex_digit(char c) {
  return is_digit(c) || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F');
}

// bytes TinyXML 1 takes for one character in UTF-8 mode (TiXmlBase::utf8ByteTable)
std::size_t utf8_length(char lead) {
  const auto u = static_cast<unsigned char>(lead);
  if (u >= 0xC2 && u <= 0xDF) return 2;
  if (u >= 0xE0 && u <= 0xEF) return 3;
  if (u >= 0xF0 && u <= 0xF4) return 4;
  return 1;
}

// 1 + the number of line breaks before `at`
int line_at(std::string_view text, std::size_t at) {
  const std::string_view before = text.substr(0, at);
  return 1 + static_cast<int>(std::count(before.begin(), before.end(), '\n'));
}

// One pass of TinyXML 1's parser (TiXmlDocument::Parse and the Parse methods it calls) over the
// text, in one encoding, keeping only the element depth and the attribute counts. Each method
// below names the TinyXML function it follows and returns where that function leaves the text,
// or kStop.
class TinyXml1Scan {
 public:
  TinyXml1Scan(std::string_view text, bool utf8, const XmlLimits& limits)
      : s_(text), utf8_(utf8), limits_(limits) {}

  // from `i` at document level to the end, an error, or the first element beyond a limit
  void run(std::size_t i) {
    i = skip_space(i);
    while (at(i) != '\0') {
      if (at(i) != '<') {
        if (depth_ == 0) return;  // the document holds only markup: TinyXML stops
        const std::size_t next = text(i, '<', true);
        if (next == kStop) return;
        i = next - 1;  // TiXmlText::Parse leaves the '<'
      } else if (depth_ > 0 && at(i + 1) == '/') {
        // an end tag: TinyXML accepts only "</name>" and stops at anything else, so the first '>'
        // ends it wherever TinyXML goes on
        const std::size_t gt = s_.find('>', i);
        if (gt == std::string_view::npos) return;
        i = gt + 1;
        --depth_;
      } else {
        i = markup(i);
        if (i == kStop) return;
      }
      i = skip_space(i);
    }
  }

  // what was found; `line` from `excess_at_`
  XmlPrescan result() const {
    XmlPrescan out;
    out.excess = excess_;
    out.line = excess_at_ == kStop ? 0 : line_at(s_, excess_at_);
    out.depth = max_depth_;
    out.attributes = max_attributes_;
    return out;
  }

  std::size_t first_declaration_end() const { return first_declaration_end_; }  // or kStop

 private:
  char at(std::size_t i) const { return i < s_.size() ? s_[i] : '\0'; }

  bool starts_with(std::size_t i, std::string_view prefix) const {
    return i <= s_.size() && s_.substr(i, prefix.size()) == prefix;
  }

  // TiXmlBase::StringEqual ignoring case, for an ASCII prefix
  bool starts_with_nocase(std::size_t i, std::string_view prefix) const {
    for (std::size_t k = 0; k < prefix.size(); ++k) {
      const char c = at(i + k);
      if (c == '\0' || std::tolower(static_cast<unsigned char>(c)) != prefix[k]) return false;
    }
    return true;
  }

  // TiXmlBase::SkipWhiteSpace: in UTF-8 mode byte-order marks count as white space
  std::size_t skip_space(std::size_t i) const {
    for (;;) {
      if (utf8_ && at(i) == '\xEF' &&
          ((at(i + 1) == '\xBB' && at(i + 2) == '\xBF') ||
           (at(i + 1) == '\xBF' && (at(i + 2) == '\xBE' || at(i + 2) == '\xBF')))) {
        i += 3;
      } else if (at(i) != '\0' && is_space(at(i))) {
        ++i;
      } else {
        return i;
      }
    }
  }

  // TiXmlBase::GetChar: one character; in UTF-8 mode a lead byte takes its whole sequence,
  // whatever follows it (even the end of the text)
  std::size_t next_char(std::size_t i) const {
    const std::size_t n = utf8_ ? utf8_length(at(i)) : 1;
    if (n > 1) return i + n;
    return at(i) == '&' ? entity_end(i) : i + 1;
  }

  // TiXmlBase::GetEntity: "&#x<hex>;" and "&#<digits>;" end at the first ';', and only the
  // characters after the last 'x' (or '#') before it must be digits
  std::size_t entity_end(std::size_t i) const {
    if (at(i + 1) == '#' && at(i + 2) != '\0') {
      const bool hex = at(i + 2) == 'x';
      if (hex && at(i + 3) == '\0') return kStop;
      const std::size_t semicolon = s_.find(';', hex ? i + 3 : i + 2);
      if (semicolon == std::string_view::npos) return kStop;
      const char mark = hex ? 'x' : '#';
      for (std::size_t k = semicolon - 1; s_[k] != mark; --k) {
        if (!(hex ? is_hex_digit(s_[k]) : is_digit(s_[k]))) return kStop;
      }
      return semicolon + 1;
    }
    for (std::string_view named : {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"}) {
      if (starts_with(i, named)) return i + named.size();
    }
    return i + 1;
  }

  // TiXmlBase::ReadText up to a one-character end mark, which it steps over (even when the text
  // ended first); `condense` is TinyXML's default white-space handling of element text
  std::size_t text(std::size_t i, char end, bool condense) const {
    if (condense) i = skip_space(i);
    for (;;) {
      const char c = at(i);
      if (c == '\0' || c == end) return i + 1;
      i = condense && is_space(c) ? i + 1 : next_char(i);
      if (i == kStop) return kStop;
    }
  }

  // TiXmlBase::ReadName
  std::size_t name(std::size_t i) const {
    if (!is_name_start(at(i))) return kStop;
    while (is_name_char(at(i))) ++i;
    return i;
  }

  // TiXmlAttribute::Parse: name = "value", 'value' or an unquoted value
  std::size_t attribute(std::size_t i) const {
    i = name(skip_space(i));
    if (i == kStop || at(i) == '\0') return kStop;
    i = skip_space(i);
    if (at(i) != '=') return kStop;
    i = skip_space(i + 1);
    const char quote = at(i);
    if (quote == '\0') return kStop;
    if (quote == '\'' || quote == '"') return text(i + 1, quote, false);
    for (; at(i) != '\0' && !is_space(at(i)) && at(i) != '/' && at(i) != '>'; ++i) {
      if (at(i) == '\'' || at(i) == '"') return kStop;
    }
    return i;
  }

  // TiXmlElement::Parse up to its content: where the tag ends, and whether content follows
  // (false for "<name/>"). TinyXML looks each attribute up among the earlier ones.
  std::pair<std::size_t, bool> start_tag(const std::size_t start) {
    std::size_t i = name(skip_space(start + 1));
    if (i == kStop || at(i) == '\0') return {kStop, false};
    for (int count = 1;; ++count) {
      i = skip_space(i);
      if (at(i) == '\0') return {kStop, false};
      if (at(i) == '/') return {at(i + 1) == '>' ? i + 2 : kStop, false};
      if (at(i) == '>') return {i + 1, true};
      i = attribute(i);
      if (i == kStop || at(i) == '\0') return {kStop, false};
      max_attributes_ = std::max(max_attributes_, count);
      if (count > limits_.attributes)
        return {stop_at(start, XmlPrescan::Excess::kAttributes), false};
    }
  }

  std::size_t stop_at(std::size_t element, XmlPrescan::Excess excess) {
    excess_ = excess;
    excess_at_ = element;
    return kStop;
  }

  // TiXmlDeclaration::Parse: ends at the first '>' outside the values of version, encoding and
  // standalone (not at "?>")
  std::size_t declaration(std::size_t i) const {
    i += 5;  // "<?xml"
    while (at(i) != '\0') {
      if (at(i) == '>') return i + 1;
      i = skip_space(i);
      if (starts_with_nocase(i, "version") || starts_with_nocase(i, "encoding") ||
          starts_with_nocase(i, "standalone")) {
        i = attribute(i);
        if (i == kStop) return kStop;
      } else {
        while (at(i) != '\0' && at(i) != '>' && !is_space(at(i))) ++i;
      }
    }
    return kStop;
  }

  // from `i` past the end of `mark`, found at or after `from` (TinyXML's comment, CDATA and
  // unknown markup end at their first mark; unterminated ones end the text)
  std::size_t past(std::size_t from, std::string_view mark) const {
    const std::size_t found = from <= s_.size() ? s_.find(mark, from) : std::string_view::npos;
    return found == std::string_view::npos ? kStop : found + mark.size();
  }

  // TiXmlNode::Identify, then the Parse method of what it found
  std::size_t markup(std::size_t i) {
    if (starts_with_nocase(i, "<?xml")) {
      const std::size_t next = declaration(i);
      if (depth_ == 0 && first_declaration_end_ == kStop) first_declaration_end_ = next;
      return next;
    }
    if (starts_with(i, "<!--")) return past(i + 4, "-->");
    if (starts_with(i, "<![CDATA[")) return past(i + 9, "]]>");
    if (starts_with(i, "<!") || !is_name_start(at(i + 1))) return past(i + 1, ">");
    // an element: TinyXML is one call deeper while it reads it, even when it is empty
    max_depth_ = std::max(max_depth_, depth_ + 1);
    if (depth_ + 1 > limits_.depth) return stop_at(i, XmlPrescan::Excess::kDepth);
    const auto [next, has_content] = start_tag(i);
    if (next != kStop && has_content) ++depth_;
    return next;
  }

  std::string_view s_;
  bool utf8_;
  XmlLimits limits_;
  int depth_ = 0;
  int max_depth_ = 0;
  int max_attributes_ = 0;
  XmlPrescan::Excess excess_ = XmlPrescan::Excess::kNone;
  std::size_t excess_at_ = kStop;
  std::size_t first_declaration_end_ = kStop;
};

// tinyxml2's tokenizer (XMLDocument::Identify and the ParseDeep methods), counting attributes
// only: its own depth limit keeps its recursion bounded. Markup ends at its first end mark
// ("?>", "-->", "]]>", ">", a value's closing quote), and any error ends the parse.
class TinyXml2Scan {
 public:
  TinyXml2Scan(std::string_view text, int limit) : s_(text), limit_(limit) {}

  void run() {
    std::size_t i = s_.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
    while (i != kStop) {
      i = skip_space(i);
      if (i >= s_.size()) return;
      if (s_[i] != '<') {
        i = s_.find('<', i);  // text
      } else if (s_.substr(i, 2) == "<?") {
        i = past(i + 2, "?>");
      } else if (s_.substr(i, 4) == "<!--") {
        i = past(i + 4, "-->");
      } else if (s_.substr(i, 9) == "<![CDATA[") {
        i = past(i + 9, "]]>");
      } else if (s_.substr(i, 2) == "<!") {
        i = past(i + 2, ">");
      } else {
        i = tag(i);
      }
    }
  }

  int max_attributes() const { return max_; }
  std::size_t too_many_at() const { return too_many_at_; }  // kStop when never too many

 private:
  char at(std::size_t i) const { return i < s_.size() ? s_[i] : '\0'; }

  // XMLUtil::IsNameStartChar, IsNameChar and IsWhiteSpace
  static bool is_name_start(char c) {
    const auto u = static_cast<unsigned char>(c);
    return u >= 128 || std::isalpha(u) || c == ':' || c == '_';
  }
  static bool is_name_char(char c) {
    return is_name_start(c) || is_digit(c) || c == '.' || c == '-';
  }
  std::size_t skip_space(std::size_t i) const {
    for (;; ++i) {
      const auto u = static_cast<unsigned char>(at(i));
      if (u == 0 || (u >= 0x80 && u < 0xC0) || !std::isspace(u)) return i;
    }
  }

  std::size_t past(std::size_t from, std::string_view mark) const {
    const std::size_t found = s_.find(mark, from);
    return found == std::string_view::npos ? kStop : found + mark.size();
  }

  // XMLElement::ParseDeep and ParseAttributes: "<name attributes>", "</name attributes>" or
  // "<name attributes/>"; each attribute is looked up among the earlier ones
  std::size_t tag(const std::size_t start) {
    std::size_t i = skip_space(start + 1);
    if (at(i) == '/') ++i;
    if (!is_name_start(at(i))) return kStop;
    while (is_name_char(at(i))) ++i;
    for (int count = 1;; ++count) {
      i = skip_space(i);
      if (at(i) == '>') return i + 1;
      if (at(i) == '/' && at(i + 1) == '>') return i + 2;
      if (!is_name_start(at(i))) return kStop;
      while (is_name_char(at(i))) ++i;
      i = skip_space(i);
      if (at(i) != '=') return kStop;
      i = skip_space(i + 1);
      const char quote = at(i);
      if (quote != '"' && quote != '\'') return kStop;
      i = past(i + 1, std::string_view(&quote, 1));
      if (i == kStop) return kStop;
      max_ = std::max(max_, count);
      if (count > limit_) {
        too_many_at_ = start;
        return kStop;
      }
    }
  }

  std::string_view s_;
  int limit_;
  int max_ = 0;
  std::size_t too_many_at_ = kStop;
};

// TinyXML 1: byte by byte until the first declaration, and then UTF-8 or not as the declaration
// says; UTF-8 from the start after a byte-order mark
XmlPrescan scan_tinyxml1(std::string_view text, const XmlLimits& limits) {
  const bool bom = text.substr(0, 3) == "\xEF\xBB\xBF";
  TinyXml1Scan bytes(text, bom, limits);
  bytes.run(0);
  XmlPrescan out = bytes.result();
  if (bom || out.excess != XmlPrescan::Excess::kNone || bytes.first_declaration_end() == kStop) {
    return out;
  }
  TinyXml1Scan utf8(text, true, limits);
  utf8.run(bytes.first_declaration_end());
  const XmlPrescan after = utf8.result();
  if (after.excess != XmlPrescan::Excess::kNone) return after;
  out.depth = std::max(out.depth, after.depth);
  out.attributes = std::max(out.attributes, after.attributes);
  return out;
}

}  // namespace

XmlPrescan prescan_xml(std::string_view text, const XmlLimits& limits) {
  text = text.substr(0, text.find('\0'));
  XmlPrescan out = scan_tinyxml1(text, limits);
  if (out.excess != XmlPrescan::Excess::kNone) return out;
  TinyXml2Scan two(text, limits.attributes);
  two.run();
  out.attributes = std::max(out.attributes, two.max_attributes());
  if (two.too_many_at() != kStop) {
    out.excess = XmlPrescan::Excess::kAttributes;
    out.line = line_at(text, two.too_many_at());
  }
  return out;
}

std::string tinyxml_input(std::string_view text) {
  std::string out(text.substr(0, text.find('\0')));
  out.append(16, '\0');  // TinyXML 1 steps at most 4 bytes past the end, then reads a NUL
  return out;
}

}  // namespace io
