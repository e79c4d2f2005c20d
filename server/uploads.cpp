#include "server/uploads.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

#include "io/assimp_import.hpp"
#include "io/bvh.hpp"
#include "io/model_file.hpp"
#include "server/security.hpp"

namespace server {
namespace fs = std::filesystem;

namespace {

std::string extension_of(const std::string& file_name) {
  std::string ext = fs::path(file_name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// A private folder holding one uploaded file; removed with everything in it when it goes.
class TempUpload {
 public:
  TempUpload(const std::string& temp_root, const std::string& ext, const std::string& bytes) {
    const fs::path root = temp_root.empty() ? fs::temp_directory_path() : fs::path(temp_root);
    fs::create_directories(root);
    std::string pattern = (root / "pindrag-upload-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::system_error(errno, std::generic_category(), pattern);
    dir_ = pattern;
    file_ = (dir_ / ("upload" + ext)).string();
    const int fd =
        ::open(file_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
    if (fd < 0) throw std::system_error(errno, std::generic_category(), file_);
    size_t written = 0;
    while (written < bytes.size()) {
      const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
      if (n <= 0) {
        ::close(fd);
        throw std::system_error(errno, std::generic_category(), file_);
      }
      written += static_cast<size_t>(n);
    }
    ::close(fd);
  }
  ~TempUpload() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempUpload(const TempUpload&) = delete;
  TempUpload& operator=(const TempUpload&) = delete;
  const std::string& file() const { return file_; }

 private:
  fs::path dir_;
  std::string file_;
};

bool is_assimp_format(const std::string& ext) {
  return ext == ".glb" || ext == ".gltf" || ext == ".fbx" || ext == ".dae";
}

// Loader messages name our temporary file; the client knows its own file name.
std::string rename_source(std::string message,
                          const std::string& temp_file,
                          const std::string& file_name) {
  for (size_t at = message.find(temp_file); at != std::string::npos;
       at = message.find(temp_file, at)) {
    message.replace(at, temp_file.size(), file_name);
    at += file_name.size();
  }
  return message;
}

bool same_skeleton(const core::Model& a, const core::Model& b) {
  return a.njoints == b.njoints && a.nq == b.nq && a.link_name == b.link_name &&
         a.joint_type == b.joint_type && a.parent == b.parent;
}

}  // namespace

std::unique_ptr<animator::Session> session_from_file(const std::string& path,
                                                     const std::string& name) {
  const std::string ext = extension_of(path);
  if (ext == ".bvh") {
    io::BvhImport imported = io::load_bvh_file(path);
    auto session = std::make_unique<animator::Session>(imported.model, name);
    if (imported.clip.size() > 1) session->set_clip(std::move(imported.clip), "import clip");
    return session;
  }
  if (is_assimp_format(ext)) {
    io::SkinnedImport imported = io::import_skinned_file(path);
    auto session = std::make_unique<animator::Session>(imported.model, name);
    session->set_skin(std::make_shared<const core::SkinnedMesh>(std::move(imported.mesh)));
    if (!imported.clips.empty() && imported.clips.front().clip.size() > 1) {
      session->set_clip(std::move(imported.clips.front().clip), "import clip");
    }
    return session;
  }
  return std::make_unique<animator::Session>(io::load_model_file(path).model, name);
}

std::unique_ptr<animator::Session> session_from_upload(const std::string& field,
                                                       const std::string& file_name,
                                                       const std::string& bytes,
                                                       const std::string& temp_root) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  if (ext != ".urdf" && ext != ".json" && ext != ".bvh" && !is_assimp_format(ext)) {
    throw UploadError(
        415, field + ": \"" + shown +
                 "\": unsupported file type (rule: .urdf, .json, .bvh, .glb, .gltf, .fbx or .dae)");
  }
  if (bytes.empty()) throw UploadError(400, field + ": \"" + shown + "\" is empty");
  const std::string name = safe_file_name(fs::path(file_name).stem().string(), "character");
  TempUpload upload(temp_root, ext, bytes);
  try {
    return session_from_file(upload.file(), name);
  } catch (const std::exception& e) {
    throw UploadError(422, field + ": " + rename_source(e.what(), upload.file(), shown));
  }
}

core::Clip clip_from_upload(const std::string& field,
                            const std::string& file_name,
                            const std::string& bytes,
                            const core::Model& model,
                            const std::string& temp_root) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  if (ext != ".bvh" && !is_assimp_format(ext)) {
    throw UploadError(415, field + ": \"" + shown +
                               "\": unsupported file type (rule: .bvh, .glb, .gltf, .fbx or .dae)");
  }
  if (bytes.empty()) throw UploadError(400, field + ": \"" + shown + "\" is empty");
  TempUpload upload(temp_root, ext, bytes);
  std::shared_ptr<const core::Model> clip_model;
  core::Clip clip;
  try {
    if (ext == ".bvh") {
      io::BvhImport imported = io::load_bvh_file(upload.file());
      clip_model = imported.model;
      clip = std::move(imported.clip);
    } else {
      io::SkinnedImport imported = io::import_skinned_file(upload.file());
      if (imported.clips.empty())
        throw UploadError(422, field + ": \"" + shown + "\" holds no animation");
      clip_model = imported.model;
      clip = std::move(imported.clips.front().clip);
    }
  } catch (const UploadError&) {
    throw;
  } catch (const std::exception& e) {
    throw UploadError(422, field + ": " + rename_source(e.what(), upload.file(), shown));
  }
  if (!same_skeleton(*clip_model, model)) {
    throw UploadError(422, field + ": \"" + shown + "\": its skeleton (" +
                               std::to_string(clip_model->nlinks()) +
                               " links) does not match the session's character (" +
                               std::to_string(model.nlinks()) +
                               " links; rule: same link names, parents and joint types)");
  }
  return clip;
}

}  // namespace server
