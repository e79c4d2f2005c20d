// The BVH reader's lexing (internal to io/bvh_*.cpp): words of the hierarchy and the MOTION
// header, and the numbers of OFFSETs and motion lines.
#pragma once

#include <array>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace io::bvh_detail {

/// A token as it appears in a message: quoted, at most 40 bytes, non-printable bytes as \xNN.
std::string show(std::string_view s);

/// One word of the hierarchy or the MOTION header.
struct Token {
  std::string_view text;  // empty at the end of the input
  int line = 0;
  bool end() const { return text.empty(); }
};

/// Whitespace-separated words, with '{' and '}' always tokens of their own. Counts lines, skips a
/// UTF-8 byte-order mark, and refuses control characters and lines over kMaxBvhLineBytes.
class Tokenizer {
 public:
  Tokenizer(std::string_view text, const std::string& source);

  /// @throws ModelError "<source>: line <line>: <what>"
  [[noreturn]] void fail(int line, const std::string& what) const;

  const Token& peek() {
    if (!peeked_) peeked_ = scan();
    return *peeked_;
  }
  Token next() {
    const Token t = peek();
    peeked_.reset();
    return t;
  }
  /// Byte offset just past the last consumed token (only valid with nothing peeked).
  std::size_t position() const { return pos_; }
  int line() const { return line_; }

 private:
  Token scan();
  void check_line_length(std::size_t at) const;

  std::string_view text_;
  const std::string& source_;
  std::size_t pos_ = 0;
  int line_ = 1;
  std::size_t line_start_ = 0;
  std::optional<Token> peeked_;
};

enum class NumberStatus { kOk, kNotANumber, kOutOfRange };

/// The number that occupies exactly [b, e). Plain decimals with at most 15 significant digits and
/// 22 decimals take the exact fast path (both m and 10^k are exact doubles, so m / 10^k is
/// correctly rounded, as Clinger's fast path); anything else goes to std::from_chars. Inline: the
/// motion reader calls it for every value.
inline NumberStatus parse_number(const char* b, const char* e, double& out) {
  static constexpr std::array<double, 23> kPow10 = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                                    1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                                    1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
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

}  // namespace io::bvh_detail
