// Bounded JSON parsing, the first half of io/json_reader.hpp: text to a document with caps on
// size, nesting and value count, duplicate keys refused (nlohmann's own parser keeps the last
// one), and errors that give the line and column of a syntax error or the JSON pointer of the
// value that broke a cap. The parser does not recurse, so deep input cannot overflow the stack.
#pragma once

#include <cstddef>
#include <nlohmann/json_fwd.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace io {

/// Deepest nesting of arrays and objects accepted by default (the character format needs 7).
constexpr int kMaxJsonDepth = 64;
/// Most JSON values (numbers, strings, arrays, ...) one document may hold by default.
constexpr std::size_t kMaxJsonValues = std::size_t{1} << 22;

/// Caps of one document; each format chooses its own.
struct JsonLimits {
  std::size_t max_bytes = std::size_t{16} << 20;  // file or text size
  int max_depth = kMaxJsonDepth;                  // nesting of arrays and objects
  std::size_t max_values = kMaxJsonValues;        // values of every kind, containers included
};

/// A document refused before any field was read. what() is "<source>: <where>: <rule>", where
/// <where> is "line L, column C" for a syntax error, "line L, column C: <pointer>" for nesting
/// too deep, the JSON pointer ("document root" for "") for a duplicate key or too many values,
/// and nothing for text over the size cap.
class JsonParseError : public std::runtime_error {
 public:
  enum class Kind { kSize, kSyntax, kDepth, kValues, kDuplicateKey };
  JsonParseError(Kind kind,
                 std::string source,
                 std::size_t line,
                 std::size_t column,
                 std::string pointer,
                 std::string rule);
  Kind kind;
  std::string source;
  std::size_t line = 0, column = 0;  // 1-based, in characters; 0 when the error has no position
  std::string pointer;  // JSON pointer of the offending value (kDepth, kValues, kDuplicateKey)
  std::string rule;     // what is wrong, without source, position or pointer
};

/// Parses `text` within `limits` (its size included). `source` names the text in messages.
/// @throws JsonParseError
nlohmann::json parse_json(std::string_view text,
                          const std::string& source,
                          const JsonLimits& limits = {});

/// Reads `path` through io::read_file (refused above limits.max_bytes before reading) and parses
/// it. `what` names the kind of file in the size message ("a request file").
/// @throws FileError (io/read_file.hpp) or JsonParseError, both naming the path
nlohmann::json read_json_file(const std::string& path,
                              const JsonLimits& limits = {},
                              const std::string& what = "a JSON file");

/// The JSON pointer (RFC 6901) of member `key`, or element `index`, of the value at `parent`.
std::string json_pointer(const std::string& parent, std::string_view key);
std::string json_pointer(const std::string& parent, std::size_t index);

/// 1-based line and column (in characters, not bytes) of a byte offset of `text`.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset);

/// `s` with control bytes and bytes outside ASCII escaped as \xNN and cut after `max_len`
/// bytes, so a message never carries raw binary.
std::string printable(std::string_view s, std::size_t max_len = 200);

/// `s` in single quotes, printable and at most 80 bytes: names inside messages.
std::string in_quotes(std::string_view s);

/// `x` in shortest round-trip form as JSON writes it ("2.0", "0.001"), -0 written as 0.
std::string json_number(double x);

/// `x` for messages: json_number without a trailing ".0" ("2", "0.001").
std::string message_number(double x);

}  // namespace io
