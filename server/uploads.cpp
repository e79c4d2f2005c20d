#include "server/uploads.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

#include "animator/marker_trial.hpp"
#include "animator/retarget.hpp"
#include "core/model_edit.hpp"
#include "io/assimp_import.hpp"
#include "io/bvh.hpp"
#include "io/c3d.hpp"
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

// the cap of a file type and the setting that changes it
struct Cap {
  std::size_t bytes;
  const char* setting;
};

Cap cap_of(const UploadCaps& caps, const std::string& ext) {
  if (ext == ".urdf") return {caps.urdf, "pindrag serve --max-upload-urdf"};
  if (ext == ".json") return {caps.json, "pindrag serve --max-upload-json"};
  if (ext == ".bvh") return {caps.bvh, "pindrag serve --max-upload-bvh"};
  if (ext == ".gltf" || ext == ".glb") return {caps.gltf, "pindrag serve --max-upload-gltf"};
  if (ext == ".fbx") return {caps.fbx, "pindrag serve --max-upload-fbx"};
  if (ext == ".c3d") return {caps.c3d, "pindrag serve --max-upload-c3d"};
  return {caps.dae, "pindrag serve --max-upload-dae"};
}

void check_upload(const std::string& field,
                  const std::string& shown,
                  const std::string& ext,
                  const std::string& bytes,
                  const UploadCaps& caps) {
  if (bytes.empty()) throw UploadError(400, field + ": \"" + shown + "\" is empty");
  const Cap cap = cap_of(caps, ext);
  if (bytes.size() > cap.bytes) {
    throw UploadError(413, field + ": \"" + shown + "\" is " + byte_text(bytes.size()) +
                               ", over the upload cap of " + byte_text(cap.bytes) + " for " + ext +
                               " files (set by " + cap.setting + ")");
  }
}

bool same_skeleton(const core::Model& a, const core::Model& b) {
  return a.njoints == b.njoints && a.nq == b.nq && a.link_name == b.link_name &&
         a.joint_type == b.joint_type && a.parent == b.parent;
}

// `character`: the model a clip is loaded onto, whose joint types the clip's joints follow;
// `scale`: metres per file unit (empty: guessed)
io::BvhImport load_bvh(const std::string& path,
                       const animator::Limits& limits,
                       const core::Model* character = nullptr,
                       std::optional<double> scale = {}) {
  io::BvhImportOptions options;
  options.scale = scale;
  options.budget = animator::clip_budget(limits);
  options.joint_types_of = character;
  return io::load_bvh_file(path, options);
}

io::SkinnedImport load_skinned(const std::string& path, const animator::Limits& limits) {
  io::ImportOptions options;
  options.budget = animator::clip_budget(limits);
  return io::import_skinned_file(path, io::ImportLimits{}, options);
}

}  // namespace

std::size_t UploadCaps::largest() const { return std::max({urdf, json, bvh, gltf, fbx, dae, c3d}); }

std::string byte_text(std::size_t bytes) {
  constexpr std::size_t kMiB = std::size_t{1} << 20;
  if (bytes >= kMiB && bytes % kMiB == 0) return std::to_string(bytes / kMiB) + " MiB";
  return std::to_string(bytes) + " bytes";
}

std::unique_ptr<animator::Session> session_from_file(const std::string& path,
                                                     const std::string& name,
                                                     const animator::Limits& limits,
                                                     std::optional<double> bvh_scale) {
  const std::string ext = extension_of(path);
  if (ext == ".bvh") {
    io::BvhImport imported = load_bvh(path, limits, nullptr, bvh_scale);
    auto session = std::make_unique<animator::Session>(imported.model, name);
    session->set_limits(limits);
    session->set_bvh_source(std::make_shared<const io::BvhLayout>(std::move(imported.layout)));
    if (imported.clip.size() > 1) session->set_clip(std::move(imported.clip), "import clip");
    return session;
  }
  if (is_assimp_format(ext)) {
    io::SkinnedImport imported = load_skinned(path, limits);
    auto session = std::make_unique<animator::Session>(imported.model, name);
    session->set_limits(limits);
    session->set_skin(std::make_shared<const core::SkinnedMesh>(std::move(imported.mesh)));
    if (!imported.clips.empty() && imported.clips.front().clip.size() > 1) {
      session->set_clip(std::move(imported.clips.front().clip), "import clip");
    }
    return session;
  }
  std::shared_ptr<const core::Model> model = io::load_model_file(path).model;
  // a robot description puts its root at the world origin: stand it on the ground (legged ones
  // on a free root)
  if (ext == ".urdf") model = core::stand_on_ground(model).model;
  auto session = std::make_unique<animator::Session>(std::move(model), name);
  session->set_limits(limits);
  return session;
}

std::unique_ptr<animator::Session> session_from_upload(const std::string& field,
                                                       const std::string& file_name,
                                                       const std::string& bytes,
                                                       const std::string& temp_root,
                                                       const UploadRules& rules,
                                                       std::optional<double> bvh_scale) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  if (ext != ".urdf" && ext != ".json" && ext != ".bvh" && !is_assimp_format(ext)) {
    throw UploadError(
        415, field + ": \"" + shown +
                 "\": unsupported file type (rule: .urdf, .json, .bvh, .glb, .gltf, .fbx or .dae)");
  }
  check_upload(field, shown, ext, bytes, rules.caps);
  const std::string name = safe_file_name(fs::path(file_name).stem().string(), "character");
  TempUpload upload(temp_root, ext, bytes);
  try {
    return session_from_file(upload.file(), name, rules.limits, bvh_scale);
  } catch (const std::exception& e) {
    throw UploadError(422, field + ": " + rename_source(e.what(), upload.file(), shown));
  }
}

ClipUpload clip_from_upload(const std::string& field,
                            const std::string& file_name,
                            const std::string& bytes,
                            const core::Model& model,
                            const std::string& temp_root,
                            const UploadRules& rules,
                            bool retarget) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  if (ext != ".bvh" && ext != ".c3d" && !is_assimp_format(ext)) {
    throw UploadError(
        415, field + ": \"" + shown +
                 "\": unsupported file type (rule: .bvh, .glb, .gltf, .fbx, .dae or .c3d)");
  }
  check_upload(field, shown, ext, bytes, rules.caps);
  if (ext == ".c3d") {
    // a marker trial: read from memory (no assimp, no temporary file) and fitted onto the
    // session's character
    try {
      const io::C3dTrial trial = io::parse_c3d(bytes, shown, animator::clip_budget(rules.limits));
      animator::FittedTrial fitted = animator::fit_trial(trial, model);
      return {std::move(fitted.clip), std::move(fitted.markers)};
    } catch (const std::exception& e) {
      throw UploadError(422, field + ": " + std::string(e.what()));
    }
  }
  TempUpload upload(temp_root, ext, bytes);
  std::shared_ptr<const core::Model> clip_model;
  core::Clip clip;
  try {
    if (ext == ".bvh") {
      io::BvhImport imported = load_bvh(upload.file(), rules.limits, &model);
      clip_model = imported.model;
      clip = std::move(imported.clip);
    } else {
      io::SkinnedImport imported = load_skinned(upload.file(), rules.limits);
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
  if (!same_skeleton(*clip_model, model) && retarget) {
    try {
      return {animator::retarget(*clip_model, clip, model).clip, nullptr};
    } catch (const std::exception& e) {
      throw UploadError(422, field + ": \"" + shown + "\": cannot be retargeted onto the " +
                                 "session's character: " + e.what());
    }
  }
  if (!same_skeleton(*clip_model, model)) {
    throw UploadError(
        422,
        field + ": \"" + shown + "\": its skeleton (" + std::to_string(clip_model->nlinks()) +
            " links) does not match the session's character (" + std::to_string(model.nlinks()) +
            " links; rule: same link names, parents and joint types)",
        "skeleton_differs");
  }
  return {std::move(clip), nullptr};
}

}  // namespace server
