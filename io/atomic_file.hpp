// Writing a file so that readers see either the old contents or the new, never a torn file.
#pragma once

#include <cstddef>
#include <string>

#include "io/core_names.hpp"

namespace io {

/// Writes `size` bytes to a fresh temporary file beside `path` (same file system), fsyncs it,
/// renames it over `path` and fsyncs the folder, so the rename itself survives a crash.
/// The file is created with `mode` (less the umask). On failure the temporary file is removed
/// and `path` is untouched.
/// @throws std::system_error naming the path and the step that failed
void write_file_atomically(const std::string& path,
                           const void* bytes,
                           std::size_t size,
                           unsigned mode = 0666);

inline void write_file_atomically(const std::string& path,
                                  const std::string& text,
                                  unsigned mode = 0666) {
  write_file_atomically(path, text.data(), text.size(), mode);
}

}  // namespace io
