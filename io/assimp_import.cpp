// The parent's side of the skinned import: checks before any process starts, the sandboxed child
// (io/assimp_child.hpp), and the decoding of its reply (io/assimp_reply.hpp).
#include "io/assimp_import.hpp"

#include <sys/stat.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <stdexcept>

#include "io/assimp_child.hpp"
#include "io/assimp_reply.hpp"

namespace io {

namespace {

// bytes of a file read to recognize its format
constexpr std::size_t kSniffBytes = 4096;

[[noreturn]] void refuse(const std::string& path, const std::string& what) {
  throw ModelError({path + ": " + what});
}

// the extension names the format; the first bytes must agree
void check_format(const std::string& path, const std::string& ext, const std::string& head) {
  const bool has_nul = head.find('\0') != std::string::npos;
  std::size_t start = 0;
  if (head.compare(0, 3, "\xEF\xBB\xBF") == 0) start = 3;
  while (start < head.size() && std::isspace(static_cast<unsigned char>(head[start]))) ++start;
  const char first = start < head.size() ? head[start] : '\0';
  if (ext == ".glb") {
    if (head.compare(0, 4, "glTF") != 0) {
      refuse(path, "not a GLB file (it does not start with 'glTF')");
    }
  } else if (ext == ".gltf") {
    if (has_nul || first != '{') refuse(path, "not a glTF JSON file (it does not start with '{')");
  } else if (ext == ".fbx") {
    const bool binary = head.compare(0, 18, "Kaydara FBX Binary") == 0;
    const bool ascii =
        !has_nul && (first == ';' || head.find("FBXHeaderExtension") != std::string::npos);
    if (!binary && !ascii) {
      refuse(
          path,
          "not an FBX file (neither the 'Kaydara FBX Binary' signature nor an ASCII FBX header)");
    }
  } else if (ext == ".dae") {
    if (has_nul || first != '<' || head.find("COLLADA") == std::string::npos) {
      refuse(path, "not a COLLADA file (no XML document with a COLLADA element at its start)");
    }
  } else {
    refuse(path, "unsupported extension '" + ext + "' (rule: .gltf, .glb, .fbx or .dae)");
  }
}

// the file exists, is regular, not empty, not larger than the limit, and its first bytes agree
// with its extension
void check_file(const std::string& path, const ImportLimits& limits) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    refuse(path, std::string("cannot open it: ") + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) refuse(path, "not a regular file");
  if (st.st_size == 0) refuse(path, "the file is empty");
  if (static_cast<std::uint64_t>(st.st_size) > limits.max_file_bytes) {
    refuse(path, std::to_string(st.st_size) + " bytes is more than the import limit of " +
                     std::to_string(limits.max_file_bytes) + " bytes");
  }
  // only the head is read here: the child reads the file itself
  std::string head(kSniffBytes, '\0');
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) refuse(path, std::string("cannot open it: ") + std::strerror(errno));
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
  }
  check_format(path, assimp_detail::lower_extension(path), head);
}

}  // namespace

SkinnedImport import_skinned_file(const std::string& path,
                                  const ImportLimits& limits,
                                  const ImportOptions& options) {
  if (!(options.frame_rate > 0 && options.frame_rate <= 1000)) {
    refuse(path, "frame rate " + std::to_string(options.frame_rate) + " is outside (0, 1000]");
  }
  if (!(options.total_mass > 0 && std::isfinite(options.total_mass))) {
    refuse(path, "total mass must be a finite number > 0");
  }
  check_file(path, limits);

  SandboxLimits sl;
  sl.memory_bytes = limits.memory_bytes;
  sl.cpu_seconds = limits.cpu_seconds;
  sl.timeout_seconds = limits.timeout_seconds;
  sl.max_reply_bytes = limits.max_reply_bytes;
  const SandboxResult r =
      run_sandboxed([&](int fd) { return assimp_detail::import_in_child(path, options, fd); }, sl);
  if (r.status != SandboxStatus::kOk) refuse(path, "the import process " + r.message);
  try {
    return assimp_detail::decode_reply(path, r.reply);
  } catch (const ModelError&) {
    throw;
  } catch (const std::exception& e) {
    refuse(path, std::string("the import process sent a malformed reply: ") + e.what());
  }
}

}  // namespace io
