#include "cli/json_fields.hpp"

#include <iostream>

#include "io/read_file.hpp"

namespace cli {

nlohmann::json read_json_file(const std::string& path, std::size_t max_bytes) {
  try {
    return io::read_json_file(path, {.max_bytes = max_bytes}, "a request file");
  } catch (const io::FileError& e) {
    throw RequestError(e.what());
  } catch (const io::JsonParseError& e) {
    // "file:line:column:", the position form editors jump to
    const std::string at =
        e.line > 0 ? path + ":" + std::to_string(e.line) + ":" + std::to_string(e.column) + ": "
                   : path + ": ";
    if (e.kind == io::JsonParseError::Kind::kSyntax)
      throw RequestError(at + "invalid JSON: " + e.rule);
    throw RequestError(at + (e.pointer.empty() ? "/" : e.pointer) + ": " + e.rule);
  }
}

io::JsonFields request_fields() {
  io::JsonFields f(io::JsonStyle{.root = "/", .wording = io::JsonWording::kRequest});
  f.set_warning_sink([](const std::string& w) { std::cerr << "warning: " << w << "\n"; });
  return f;
}

}  // namespace cli
