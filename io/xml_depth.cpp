#include "io/xml_depth.hpp"

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

// One pass of TinyXML 1's parser (TiXmlDocument::Parse and the Parse methods it calls) over the
// text, in one encoding, keeping only the element depth. Each method below names the TinyXML
// function it follows and returns where that function leaves the text, or kStop.
class Scanner {
 public:
  Scanner(std::string_view text, bool utf8, int limit) : s_(text), utf8_(utf8), limit_(limit) {}

  // from `i` at document level to the end, an error, or the first element deeper than the limit
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

  int max_depth() const { return max_depth_; }
  std::size_t too_deep_at() const { return too_deep_at_; }  // kStop when never too deep
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
  // (false for "<name/>")
  std::pair<std::size_t, bool> start_tag(std::size_t i) const {
    i = name(skip_space(i + 1));
    if (i == kStop || at(i) == '\0') return {kStop, false};
    for (;;) {
      i = skip_space(i);
      if (at(i) == '\0') return {kStop, false};
      if (at(i) == '/') return {at(i + 1) == '>' ? i + 2 : kStop, false};
      if (at(i) == '>') return {i + 1, true};
      i = attribute(i);
      if (i == kStop || at(i) == '\0') return {kStop, false};
    }
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
    if (depth_ + 1 > limit_) {
      max_depth_ = depth_ + 1;
      too_deep_at_ = i;
      return kStop;
    }
    max_depth_ = std::max(max_depth_, depth_ + 1);
    const auto [next, has_content] = start_tag(i);
    if (next != kStop && has_content) ++depth_;
    return next;
  }

  std::string_view s_;
  bool utf8_;
  int limit_;
  int depth_ = 0;
  int max_depth_ = 0;
  std::size_t too_deep_at_ = kStop;
  std::size_t first_declaration_end_ = kStop;
};

XmlNesting result_of(std::string_view text, const Scanner& scan) {
  XmlNesting out;
  out.depth = scan.max_depth();
  if (scan.too_deep_at() != kStop) {
    const std::string_view before = text.substr(0, scan.too_deep_at());
    out.line = 1 + static_cast<int>(std::count(before.begin(), before.end(), '\n'));
  }
  return out;
}

}  // namespace

XmlNesting tinyxml_nesting(std::string_view text, int limit) {
  text = text.substr(0, text.find('\0'));
  // TinyXML 1 reads UTF-8 from the start after a byte-order mark; otherwise byte by byte until
  // the first declaration, and then UTF-8 or not as the declaration says
  const bool bom = text.substr(0, 3) == "\xEF\xBB\xBF";
  Scanner bytes(text, bom, limit);
  bytes.run(0);
  XmlNesting out = result_of(text, bytes);
  if (bom || out.line != 0 || bytes.first_declaration_end() == kStop) return out;
  Scanner utf8(text, true, limit);
  utf8.run(bytes.first_declaration_end());
  const XmlNesting after = result_of(text, utf8);
  if (after.line != 0) return after;
  out.depth = std::max(out.depth, after.depth);
  return out;
}

std::string tinyxml_input(std::string_view text) {
  std::string out(text.substr(0, text.find('\0')));
  out.append(16, '\0');  // TinyXML 1 steps at most 4 bytes past the end, then reads a NUL
  return out;
}

}  // namespace io
