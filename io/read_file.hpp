// One bounded file reader for every format: the whole file as bytes, refused before reading when
// it is larger than the caller's cap. Errors name the file and, for the cap, the limit and what
// it is for.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace io {

/// A file that cannot be read, or is larger than its cap. what() starts with the path.
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The bytes of `path`, at most `max_bytes` of them. `what` names the kind of file in the size
/// message ("a BVH file is at most 268435456 bytes").
/// @throws FileError "<path>: cannot open the file: <reason>", "<path>: is a directory",
///         "<path>: file is N bytes (rule: <what> is at most max_bytes bytes)"
std::string read_file(const std::string& path,
                      std::size_t max_bytes,
                      const std::string& what = "a file");

}  // namespace io
