#include "io/json_parse.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "io/read_file.hpp"

namespace io {

namespace {

using Json = nlohmann::json;

std::string shown_pointer(const std::string& pointer) {
  return pointer.empty() ? "document root" : pointer;
}

std::string where(JsonParseError::Kind kind,
                  std::size_t line,
                  std::size_t column,
                  const std::string& pointer) {
  using Kind = JsonParseError::Kind;
  const std::string position =
      "line " + std::to_string(line) + ", column " + std::to_string(column) + ": ";
  switch (kind) {
    case Kind::kSize:
      return "";
    case Kind::kSyntax:
      return position;
    case Kind::kDepth:
      return position + shown_pointer(pointer) + ": ";
    case Kind::kValues:
    case Kind::kDuplicateKey:
      return shown_pointer(pointer) + ": ";
  }
  return "";
}

// Byte offset of the first bracket that opens nesting level max_depth + 1 (outside strings).
std::size_t depth_overflow_offset(std::string_view text, int max_depth) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return text.size();
}

// nlohmann's message without its "[json.exception.x.y] parse error at line l, column c: " head
// (the position is reported from the byte offset instead).
std::string clean_parser_message(const std::string& what) {
  std::string_view m = what;
  if (m.rfind("[json.exception.", 0) == 0) {
    const std::size_t close = m.find("] ");
    if (close != std::string_view::npos) m.remove_prefix(close + 2);
  }
  if (m.rfind("parse error", 0) == 0) {
    const std::size_t colon = m.find(": ");
    if (colon != std::string_view::npos) m.remove_prefix(colon + 2);
  }
  return printable(m);
}

struct Failure {
  JsonParseError::Kind kind = JsonParseError::Kind::kSyntax;
  bool failed = false;
  std::size_t position = 0;  // characters read when the syntax error was found
  std::string pointer;
  std::string rule;
};

// A SAX handler that builds the document while enforcing the depth and value caps and refusing
// duplicate keys. It keeps its own stack of open containers, so nothing recurses.
class DomBuilder final : public nlohmann::json_sax<Json> {
 public:
  explicit DomBuilder(const JsonLimits& limits) : limits_(limits) {}

  Json root;
  Failure failure;

  bool null() override { return add(Json(nullptr)) != nullptr; }
  bool boolean(bool b) override { return add(Json(b)) != nullptr; }
  bool number_integer(number_integer_t v) override { return add(Json(v)) != nullptr; }
  bool number_unsigned(number_unsigned_t v) override { return add(Json(v)) != nullptr; }
  bool number_float(number_float_t v, const string_t&) override { return add(Json(v)) != nullptr; }
  bool string(string_t& s) override { return add(Json(s)) != nullptr; }
  bool binary(binary_t&) override {  // only binary formats (CBOR, ...) produce these
    fail(JsonParseError::Kind::kSyntax, pointer_of_new(), "binary values are not JSON");
    return false;
  }
  bool start_object(std::size_t) override { return open(Json::object()); }
  bool key(string_t& k) override {
    Json& obj = *stack_.back();
    if (obj.contains(k)) {
      fail(JsonParseError::Kind::kDuplicateKey, json_pointer(pointer_of_top(), k),
           "duplicate key (rule: the keys of an object are unique)");
      return false;
    }
    keys_.back() = k;
    slot_ = &obj[k];
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(Json::array()); }
  bool end_array() override { return close(); }
  bool parse_error(std::size_t position,
                   const std::string&,
                   const nlohmann::detail::exception& ex) override {
    failure.failed = true;
    failure.kind = JsonParseError::Kind::kSyntax;
    failure.position = position;
    failure.rule = clean_parser_message(ex.what());
    return false;
  }

 private:
  void fail(JsonParseError::Kind kind, std::string pointer, std::string rule) {
    failure.failed = true;
    failure.kind = kind;
    failure.pointer = std::move(pointer);
    failure.rule = std::move(rule);
  }
  // pointer of the innermost open container
  std::string pointer_of_top() const {
    std::string p;
    for (std::size_t l = 0; l + 1 < stack_.size(); ++l) {
      if (stack_[l]->is_array())
        p = json_pointer(p, stack_[l]->size() - 1);
      else
        p = json_pointer(p, keys_[l]);
    }
    return p;
  }
  // pointer of the value about to be added
  std::string pointer_of_new() const {
    if (stack_.empty()) return "";
    const Json& top = *stack_.back();
    return top.is_array() ? json_pointer(pointer_of_top(), top.size())
                          : json_pointer(pointer_of_top(), keys_.back());
  }
  Json* add(Json&& v) {
    if (++count_ > limits_.max_values) {
      const std::string cap = std::to_string(limits_.max_values);
      fail(JsonParseError::Kind::kValues, pointer_of_new(),
           "the document holds more than " + cap + " values (rule: at most " + cap + ")");
      return nullptr;
    }
    if (stack_.empty()) {
      root = std::move(v);
      return &root;
    }
    Json& top = *stack_.back();
    if (top.is_array()) {
      auto& arr = top.get_ref<Json::array_t&>();
      arr.push_back(std::move(v));
      return &arr.back();
    }
    *slot_ = std::move(v);
    return slot_;
  }
  bool open(Json&& container) {
    if (stack_.size() >= static_cast<std::size_t>(std::max(limits_.max_depth, 0))) {
      const std::string cap = std::to_string(limits_.max_depth);
      fail(JsonParseError::Kind::kDepth, pointer_of_new(),
           "arrays and objects nest deeper than " + cap + " levels (rule: at most " + cap + ")");
      return false;
    }
    Json* p = add(std::move(container));
    if (!p) return false;
    stack_.push_back(p);
    keys_.emplace_back();
    return true;
  }
  bool close() {
    stack_.pop_back();
    keys_.pop_back();
    return true;
  }

  const JsonLimits& limits_;
  std::vector<Json*> stack_;       // open containers, outermost first
  std::vector<std::string> keys_;  // per open container: the key being filled (objects)
  Json* slot_ = nullptr;           // object member created by the last key()
  std::size_t count_ = 0;
};

}  // namespace

JsonParseError::JsonParseError(Kind kind_,
                               std::string source_,
                               std::size_t line_,
                               std::size_t column_,
                               std::string pointer_,
                               std::string rule_)
    : std::runtime_error(source_ + ": " + where(kind_, line_, column_, pointer_) + rule_),
      kind(kind_),
      source(std::move(source_)),
      line(line_),
      column(column_),
      pointer(std::move(pointer_)),
      rule(std::move(rule_)) {}

nlohmann::json parse_json(std::string_view text,
                          const std::string& source,
                          const JsonLimits& limits) {
  using Kind = JsonParseError::Kind;
  if (text.size() > limits.max_bytes) {
    throw JsonParseError(Kind::kSize, source, 0, 0, "",
                         "text is " + std::to_string(text.size()) + " bytes (rule: at most " +
                             std::to_string(limits.max_bytes) + " bytes)");
  }
  DomBuilder dom(limits);
  if (Json::sax_parse(text.begin(), text.end(), &dom, nlohmann::detail::input_format_t::json,
                      /*strict=*/true)) {
    return std::move(dom.root);
  }
  const Failure& f = dom.failure;
  switch (f.kind) {
    case Kind::kSyntax: {
      if (text.empty()) {
        throw JsonParseError(Kind::kSyntax, source, 1, 1, "",
                             "the file is empty (rule: a JSON value)");
      }
      // nlohmann counts the characters read, including the one that failed
      const auto [line, column] = line_column(text, f.position > 0 ? f.position - 1 : 0);
      throw JsonParseError(Kind::kSyntax, source, line, column, "", f.rule);
    }
    case Kind::kDepth: {
      const auto [line, column] = line_column(text, depth_overflow_offset(text, limits.max_depth));
      throw JsonParseError(Kind::kDepth, source, line, column, f.pointer, f.rule);
    }
    case Kind::kValues:
    case Kind::kDuplicateKey:
      throw JsonParseError(f.kind, source, 0, 0, f.pointer, f.rule);
    case Kind::kSize:
      break;
  }
  throw JsonParseError(Kind::kSyntax, source, 1, 1, "", "the JSON parser stopped without a reason");
}

nlohmann::json read_json_file(const std::string& path,
                              const JsonLimits& limits,
                              const std::string& what) {
  return parse_json(read_file(path, limits.max_bytes, what), path, limits);
}

std::string json_pointer(const std::string& parent, std::string_view key) {
  std::string out = parent;
  out.reserve(parent.size() + key.size() + 1);
  out += '/';
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string json_pointer(const std::string& parent, std::size_t index) {
  return parent + "/" + std::to_string(index);
}

std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line;
      column = 1;
    } else if ((c & 0xC0) != 0x80) {  // UTF-8 continuation bytes do not start a character
      ++column;
    }
  }
  return {line, column};
}

std::string printable(std::string_view s, std::size_t max_len) {
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (std::size_t i = 0; i < s.size() && i < max_len; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c >= 0x7f) {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (s.size() > max_len) out += "...";
  return out;
}

std::string in_quotes(std::string_view s) { return "'" + printable(s, 80) + "'"; }

std::string json_number(double x) {
  if (x == 0) x = 0.0;  // no "-0.0" in files or messages
  return Json(x).dump();
}

std::string message_number(double x) {
  std::string s = json_number(x);
  if (s.size() > 2 && s.compare(s.size() - 2, 2, ".0") == 0) s.resize(s.size() - 2);
  return s;
}

}  // namespace io
