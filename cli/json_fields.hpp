// Request files of the command line (`pindrag solve`, `edit`, `dynamics`), read through the
// project's JSON reader (io/json_reader.hpp) in the request style: fields named as JSON pointers,
// "/" for the whole document, nlohmann's type names ("expected a number, got string"), unknown
// keys warned about on stderr. Errors reach the commands as RequestError
// (io::rethrow_as<RequestError>).
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "io/json_reader.hpp"

namespace cli {

/// A bad request: what() names the field and the rule.
class RequestError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Largest request file accepted (bytes).
constexpr std::size_t kMaxRequestBytes = std::size_t{16} << 20;

/// Parses a request file: size-capped, depth- and value-capped, duplicate keys refused.
/// @throws RequestError "<path>: <reason>", or "<path>:<line>:<column>: invalid JSON: <reason>"
nlohmann::json read_json_file(const std::string& path, std::size_t max_bytes = kMaxRequestBytes);

/// A reader in the request style; its warnings go to stderr as "warning: <field>: <what>".
io::JsonFields request_fields();

}  // namespace cli
