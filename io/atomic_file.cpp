#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <random>
#include <system_error>

namespace io {

using namespace core;  // io reads and writes core's types

namespace {

std::system_error io_error(int err, const std::string& what) {
  return std::system_error(err, std::generic_category(), what);
}

}  // namespace

// a temporary file in the target's folder, fsync, rename over the target, fsync of the folder
void write_file_atomically(const std::string& path,
                           const void* bytes,
                           std::size_t size,
                           unsigned mode) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  if (target.filename().empty()) throw io_error(EISDIR, path + ": not a file name");
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  std::random_device rd;
  std::string tmp;
  int fd = -1;
  for (int attempt = 0; attempt < 16 && fd < 0; ++attempt) {
    char suffix[32];
    std::snprintf(suffix, sizeof suffix, ".tmp-%08x%08x", rd(), rd());
    tmp = (dir / ("." + target.filename().string() + suffix)).string();
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
    if (fd < 0 && errno != EEXIST) {
      throw io_error(errno, path + ": cannot create the temporary file " + tmp);
    }
  }
  if (fd < 0) throw io_error(EEXIST, path + ": cannot find a free temporary file name");
  auto fail = [&](const std::string& what) {
    const int err = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    throw io_error(err, path + ": " + what);
  };
  const auto* p = static_cast<const std::uint8_t*>(bytes);
  size_t done = 0;
  while (done < size) {
    const ssize_t w = ::write(fd, p + done, size - done);
    if (w < 0) {
      if (errno == EINTR) continue;
      fail("write failed");
    }
    done += static_cast<size_t>(w);
  }
  if (::fsync(fd) != 0) fail("fsync failed");
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw io_error(err, path + ": close failed");
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw io_error(err, path + ": cannot rename " + tmp + " over it");
  }
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace io
