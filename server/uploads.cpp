#include "server/uploads.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

#include "animator/facing.hpp"
#include "animator/marker_trial.hpp"
#include "animator/retarget.hpp"
#include "core/configuration.hpp"
#include "core/model_edit.hpp"
#include "io/assimp_import.hpp"
#include "io/bvh.hpp"
#include "io/c3d.hpp"
#include "io/model_file.hpp"
#include "server/security.hpp"
#include "server/upload_resources.hpp"

namespace server {
namespace fs = std::filesystem;

namespace {

std::string extension_of(const std::string& file_name) {
  return lower(fs::path(file_name).extension().string());
}

// A private folder holding one uploaded file (and the files it references); removed with
// everything in it when it goes.
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
    try {
      write_new(file_, bytes);
    } catch (...) {
      std::error_code ec;
      fs::remove_all(dir_, ec);  // the destructor does not run for a constructor that throws
      throw;
    }
  }
  /// A file beside the upload, by a name check_upload_resources accepted.
  void add(const std::string& name, const std::string& bytes) {
    write_new((dir_ / name).string(), bytes);
  }
  ~TempUpload() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempUpload(const TempUpload&) = delete;
  TempUpload& operator=(const TempUpload&) = delete;
  const std::string& file() const { return file_; }

 private:
  static void write_new(const std::string& path, const std::string& bytes) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
    if (fd < 0) throw std::system_error(errno, std::generic_category(), path);
    size_t written = 0;
    while (written < bytes.size()) {
      const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
      if (n <= 0) {
        ::close(fd);
        throw std::system_error(errno, std::generic_category(), path);
      }
      written += static_cast<size_t>(n);
    }
    ::close(fd);
  }

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

void check_upload(const std::string& field,
                  const std::string& shown,
                  const std::string& ext,
                  const std::string& bytes,
                  const UploadCaps& caps) {
  if (bytes.empty()) throw UploadError(400, field + ": \"" + shown + "\" is empty");
  const UploadCap cap = upload_cap(caps, ext);
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

// the figure stood upright (a file authored Z up lies on its back) and turned to face +Z in the
// clip's first frame (its rest pose when there is no clip)
std::shared_ptr<const core::Model> upright_facing_forward(
    const std::shared_ptr<const core::Model>& model, const std::vector<Eigen::VectorXd>& frames) {
  const std::shared_ptr<const core::Model> upright = animator::stand_upright(model);
  return animator::face_forward(
             upright, frames.empty() ? core::rest_configuration(*upright) : frames.front())
      .model;
}

io::SkinnedImport load_skinned(const std::string& path, const animator::Limits& limits) {
  io::ImportOptions options;
  options.budget = animator::clip_budget(limits);
  return io::import_skinned_file(path, io::ImportLimits{}, options);
}

}  // namespace

std::size_t UploadCaps::largest() const { return std::max({urdf, json, bvh, gltf, fbx, dae, c3d}); }

UploadCap upload_cap(const UploadCaps& caps, const std::string& ext) {
  if (ext == ".urdf") return {caps.urdf, "pindrag serve --max-upload-urdf"};
  if (ext == ".json") return {caps.json, "pindrag serve --max-upload-json"};
  if (ext == ".bvh") return {caps.bvh, "pindrag serve --max-upload-bvh"};
  if (ext == ".gltf" || ext == ".glb") return {caps.gltf, "pindrag serve --max-upload-gltf"};
  if (ext == ".fbx") return {caps.fbx, "pindrag serve --max-upload-fbx"};
  if (ext == ".c3d") return {caps.c3d, "pindrag serve --max-upload-c3d"};
  return {caps.dae, "pindrag serve --max-upload-dae"};
}

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
    // upright and facing +Z where the clip starts, and the capture's floor where its figure
    // stands: its lowest point over the clip at y = 0
    imported.model = upright_facing_forward(imported.model, imported.clip.frames);
    imported.model =
        core::stand_motion_on_ground(imported.model, imported.clip.frames, nullptr).model;
    auto session = std::make_unique<animator::Session>(imported.model, name);
    session->set_limits(limits);
    session->set_bvh_source(std::make_shared<const io::BvhLayout>(std::move(imported.layout)));
    if (imported.clip.size() > 1) session->set_clip(std::move(imported.clip), "import clip");
    return session;
  }
  if (is_assimp_format(ext)) {
    io::SkinnedImport imported = load_skinned(path, limits);
    // upright and facing +Z where the clip starts, standing on the ground: the lowest point of its
    // mesh (or links) over the clip at y = 0
    static const std::vector<Eigen::VectorXd> kNoFrames;
    const std::vector<Eigen::VectorXd>& frames =
        imported.clips.empty() ? kNoFrames : imported.clips.front().clip.frames;
    imported.model = upright_facing_forward(imported.model, frames);
    imported.model = core::stand_motion_on_ground(imported.model, frames, &imported.mesh).model;
    auto session = std::make_unique<animator::Session>(imported.model, name);
    session->set_limits(limits);
    // an animation-only file (a skeleton without its mesh) is drawn as capsules
    if (!imported.mesh.empty()) {
      session->set_skin(std::make_shared<const core::SkinnedMesh>(std::move(imported.mesh)));
    }
    if (!imported.clips.empty() && imported.clips.front().clip.size() > 1) {
      session->set_clip(std::move(imported.clips.front().clip), "import clip");
    }
    return session;
  }
  std::shared_ptr<const core::Model> model = io::load_model_file(path).model;
  // a robot description puts its root at the world origin: turn it upright and to face +Z and
  // stand it on the ground (legged ones on a free root)
  if (ext == ".urdf") {
    model = upright_facing_forward(model, {});
    model = core::stand_on_ground(model).model;
  }
  auto session = std::make_unique<animator::Session>(std::move(model), name);
  session->set_limits(limits);
  return session;
}

std::unique_ptr<animator::Session> session_from_upload(
    const std::string& field,
    const std::string& file_name,
    const std::string& bytes,
    const std::string& temp_root,
    const UploadRules& rules,
    std::optional<double> bvh_scale,
    const std::vector<UploadResource>& resources) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  if (ext != ".urdf" && ext != ".json" && ext != ".bvh" && !is_assimp_format(ext)) {
    throw UploadError(
        415, field + ": \"" + shown +
                 "\": unsupported file type (rule: .urdf, .json, .bvh, .glb, .gltf, .fbx or .dae)");
  }
  check_upload(field, shown, ext, bytes, rules.caps);
  const std::vector<StoredResource> stored =
      check_upload_resources(field, shown, ext, bytes, resources, rules.caps);
  const std::string name = safe_file_name(fs::path(file_name).stem().string(), "character");
  TempUpload upload(temp_root, ext, bytes);
  for (const StoredResource& r : stored) upload.add(r.name, r.resource->bytes);
  try {
    return session_from_file(upload.file(), name, rules.limits, bvh_scale);
  } catch (const std::exception& e) {
    throw UploadError(422, field + ": " + rename_source(e.what(), upload.file(), shown));
  }
}

namespace {

struct MotionUpload {
  std::shared_ptr<const core::Model> model;  // the clip's own skeleton
  core::Clip clip;
};

// The first clip of a motion file (.bvh or an assimp format) with its skeleton; BVH joints take
// the joint types of `character` where the names agree.
MotionUpload load_motion(const std::string& field,
                         const std::string& shown,
                         const std::string& ext,
                         const std::string& bytes,
                         const core::Model& character,
                         const std::string& temp_root,
                         const UploadRules& rules,
                         const std::vector<UploadResource>& resources) {
  const std::vector<StoredResource> stored =
      check_upload_resources(field, shown, ext, bytes, resources, rules.caps);
  TempUpload upload(temp_root, ext, bytes);
  for (const StoredResource& r : stored) upload.add(r.name, r.resource->bytes);
  try {
    if (ext == ".bvh") {
      io::BvhImport imported = load_bvh(upload.file(), rules.limits, &character);
      return {imported.model, std::move(imported.clip)};
    }
    io::SkinnedImport imported = load_skinned(upload.file(), rules.limits);
    if (imported.clips.empty())
      throw UploadError(422, field + ": \"" + shown + "\" holds no animation");
    return {imported.model, std::move(imported.clips.front().clip)};
  } catch (const UploadError&) {
    throw;
  } catch (const std::exception& e) {
    throw UploadError(422, field + ": " + rename_source(e.what(), upload.file(), shown));
  }
}

void check_motion_type(const std::string& field,
                       const std::string& shown,
                       const std::string& ext,
                       bool c3d_allowed) {
  if (ext != ".bvh" && (ext != ".c3d" || !c3d_allowed) && !is_assimp_format(ext)) {
    throw UploadError(415,
                      field + ": \"" + shown + "\": unsupported file type (rule: .bvh, .glb, " +
                          ".gltf, .fbx, .dae" + (c3d_allowed ? " or .c3d)" : " with a skeleton)"));
  }
}

}  // namespace

ClipUpload clip_from_upload(const std::string& field,
                            const std::string& file_name,
                            const std::string& bytes,
                            const core::Model& model,
                            const std::string& temp_root,
                            const UploadRules& rules,
                            bool retarget,
                            const std::vector<animator::MappingEntry>& mapping,
                            const std::vector<UploadResource>& resources) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  check_motion_type(field, shown, ext, /*c3d_allowed=*/true);
  check_upload(field, shown, ext, bytes, rules.caps);
  if (ext == ".c3d") {
    // a marker trial: read from memory (no assimp, no temporary file) and fitted onto the
    // session's character; it references no other files
    check_upload_resources(field, shown, ext, bytes, resources, rules.caps);
    try {
      const io::C3dTrial trial = io::parse_c3d(bytes, shown, animator::clip_budget(rules.limits));
      animator::FittedTrial fitted = animator::fit_trial(trial, model);
      return {std::move(fitted.clip), std::move(fitted.markers)};
    } catch (const std::exception& e) {
      throw UploadError(422, field + ": " + std::string(e.what()));
    }
  }
  MotionUpload motion = load_motion(field, shown, ext, bytes, model, temp_root, rules, resources);
  if (!same_skeleton(*motion.model, model) && retarget) {
    try {
      animator::RetargetOptions options;
      options.mapping = mapping;
      options.mapping_origin = "mapping";
      return {animator::retarget(*motion.model, motion.clip, model, options).clip, nullptr};
    } catch (const std::exception& e) {
      throw UploadError(422, field + ": \"" + shown + "\": cannot be retargeted onto the " +
                                 "session's character: " + e.what());
    }
  }
  if (!same_skeleton(*motion.model, model)) {
    throw UploadError(
        422,
        field + ": \"" + shown + "\": its skeleton (" + std::to_string(motion.model->nlinks()) +
            " links) does not match the session's character (" + std::to_string(model.nlinks()) +
            " links; rule: same link names, parents and joint types)",
        "skeleton_differs");
  }
  return {std::move(motion.clip), nullptr};
}

nlohmann::json clip_correspondence(const std::string& field,
                                   const std::string& file_name,
                                   const std::string& bytes,
                                   const core::Model& model,
                                   const std::string& temp_root,
                                   const UploadRules& rules,
                                   const std::vector<UploadResource>& resources) {
  const std::string ext = extension_of(file_name);
  const std::string shown = safe_file_name(file_name, "upload");
  check_motion_type(field, shown, ext, /*c3d_allowed=*/false);
  check_upload(field, shown, ext, bytes, rules.caps);
  const MotionUpload motion =
      load_motion(field, shown, ext, bytes, model, temp_root, rules, resources);
  const core::Model& S = *motion.model;
  const animator::Correspondence c = animator::guess_correspondence(S, model);
  nlohmann::json joints = nlohmann::json::array();
  for (int s = 1; s < S.njoints; ++s) {
    if (S.joint_type[s] == core::JointType::kFixed) continue;
    const int t = c.target_of_source[s];
    joints.push_back({{"source", S.link_name[s]},
                      {"target", t > 0 ? nlohmann::json(model.link_name[t]) : nlohmann::json()}});
  }
  nlohmann::json links = nlohmann::json::array();
  for (int t = 1; t < model.njoints; ++t) {
    if (model.joint_type[t] != core::JointType::kFixed) links.push_back(model.link_name[t]);
  }
  return {{"source_convention", c.source_parts.convention},
          {"target_convention", c.target_parts.convention},
          {"same_skeleton", same_skeleton(S, model)},
          {"joints", joints},
          {"links", links}};
}

}  // namespace server
