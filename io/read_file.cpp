#include "io/read_file.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

namespace io {

std::string read_file(const std::string& path, std::size_t max_bytes, const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) {
    throw FileError(path +
                    ": cannot open the file: " + (ec ? ec.message() : std::string("no such file")));
  }
  if (fs::is_directory(status)) throw FileError(path + ": is a directory, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path + ": cannot open the file: " + std::strerror(errno));
  // the size is checked on the open stream, so a file that grows afterwards is still capped
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  if (end < 0) throw FileError(path + ": cannot read the file size");
  const auto size = static_cast<std::uintmax_t>(end);
  if (size > max_bytes) {
    throw FileError(path + ": file is " + std::to_string(size) + " bytes (rule: " + what +
                    " is at most " + std::to_string(max_bytes) + " bytes)");
  }
  in.seekg(0);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(size));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return bytes;
}

}  // namespace io
