#include "io/bvh_tokenizer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "io/bvh_document.hpp"
#include "io/bvh_text.hpp"

namespace io::bvh_detail {

std::string show(std::string_view s) {
  std::string out = "'";
  const std::size_t n = std::min<std::size_t>(s.size(), 40);
  for (std::size_t i = 0; i < n; ++i) {
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

Tokenizer::Tokenizer(std::string_view text, const std::string& source)
    : text_(text), source_(source) {
  if (text_.size() >= 3 && std::memcmp(text_.data(), "\xEF\xBB\xBF", 3) == 0) pos_ = 3;
}

void Tokenizer::fail(int line, const std::string& what) const {
  throw ModelError({source_ + ": line " + std::to_string(line) + ": " + what});
}

Token Tokenizer::scan() {
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
  const std::size_t begin = pos_;
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

void Tokenizer::check_line_length(std::size_t at) const {
  if (at - line_start_ > kMaxBvhLineBytes) {
    fail(line_, "the line is longer than " + std::to_string(kMaxBvhLineBytes) +
                    " bytes (rule: kMaxBvhLineBytes)");
  }
}

}  // namespace io::bvh_detail
