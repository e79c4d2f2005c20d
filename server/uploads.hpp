// Uploaded files turned into characters and clips. The bytes are written to a private temporary
// folder (mode 0700) under a name the server makes, loaded with core/io (assimp formats in a
// sandboxed child process), and removed; a client never names a path.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "animator/joint_names.hpp"
#include "animator/session.hpp"
#include "core/clip.hpp"
#include "server/upload_resources.hpp"

namespace server {

/// Largest upload accepted per file type, in bytes; each is a `pindrag serve` setting
/// (docs/protocol.md, "Limits"). Text formats that describe a character alone are small; files
/// that carry motion or meshes get more room, and the clip budget bounds what their motion
/// may cost once read.
struct UploadCaps {
  std::size_t urdf = std::size_t{4} << 20;   // --max-upload-urdf
  std::size_t json = std::size_t{4} << 20;   // --max-upload-json (native character JSON)
  std::size_t bvh = std::size_t{64} << 20;   // --max-upload-bvh
  std::size_t gltf = std::size_t{64} << 20;  // --max-upload-gltf (.gltf and .glb)
  std::size_t fbx = std::size_t{64} << 20;   // --max-upload-fbx
  std::size_t dae = std::size_t{64} << 20;   // --max-upload-dae (COLLADA)
  std::size_t c3d = std::size_t{64} << 20;   // --max-upload-c3d (marker trials, fitted on upload)
  /// The largest of them: what the HTTP server reads of a request at most.
  std::size_t largest() const;
};

/// The cap of a file type (by its extension, ".gltf") and the setting that changes it.
struct UploadCap {
  std::size_t bytes;
  const char* setting;
};
UploadCap upload_cap(const UploadCaps& caps, const std::string& ext);

/// What an upload is held to: its size by type, and the session's budgets for what it brings.
struct UploadRules {
  UploadCaps caps;
  animator::Limits limits;
};

/// "64 MiB" for whole mebibytes, "1234 bytes" otherwise.
std::string byte_text(std::size_t bytes);

/// A file the server will not take; what() names the field and the rule. Maps to 4xx.
class UploadError : public std::runtime_error {
 public:
  UploadError(int http_status, const std::string& message, std::string error_code = {})
      : std::runtime_error(message), status(http_status), code(std::move(error_code)) {}
  int status;
  /// Machine-readable kind for the page to act on ("skeleton_differs"); empty for most errors.
  std::string code;
};

/// A new session named `name` from a character file on disk chosen by the operator (by
/// extension: .urdf, .json, .bvh, .glb, .gltf, .fbx, .dae; a BVH or an animated skinned file also
/// brings its first clip), held to `limits`: a clip beyond them is refused while its file is read.
/// @throws core::ModelError or std::runtime_error naming the file
/// `bvh_scale`: metres per BVH file unit; empty: guessed from the figure's size (io/bvh.hpp).
std::unique_ptr<animator::Session> session_from_file(const std::string& path,
                                                     const std::string& name,
                                                     const animator::Limits& limits = {},
                                                     std::optional<double> bvh_scale = {});

/// A new session from an uploaded character file (.urdf, .json, .bvh, .glb, .gltf, .fbx, .dae);
/// a BVH or an animated glTF/FBX/COLLADA file also brings its first clip.
/// `field` names the form field in messages. A file over its type's cap is refused with 413
/// naming the cap and its setting; a clip over the budget with 422 naming the limit.
/// `resources`: the files a .gltf references, stored beside it for the import
/// (check_upload_resources has the rules).
/// @throws UploadError
std::unique_ptr<animator::Session> session_from_upload(
    const std::string& field,
    const std::string& file_name,
    const std::string& bytes,
    const std::string& temp_root,
    const UploadRules& rules = {},
    std::optional<double> bvh_scale = {},
    const std::vector<UploadResource>& resources = {});

/// The first clip of an uploaded motion file (.bvh, .glb, .gltf, .fbx, .dae), or a marker trial
/// (.c3d) fitted onto `model` with its bundled marker set (animator::fit_trial; a character
/// without one is a 422 naming the rule). The clip must fit
/// `model` (same links, same joint types), else UploadError 422 (code "skeleton_differs") unless
/// `retarget`: a clip of another skeleton is then retargeted onto `model`
/// (animator/retarget.hpp), and one that cannot be (no recognisable legs) is a 422 naming why.
/// Caps, budget and `resources` as for session_from_upload. @throws UploadError
struct ClipUpload {
  core::Clip clip;
  std::shared_ptr<const animator::ClipMarkers> markers;  // a marker trial's, else null
};
/// `mapping`: the user's entries over the guessed correspondence when retargeting
/// (docs/retargeting.md, "Mapping file"); one naming a joint or link that is not there is a 422.
ClipUpload clip_from_upload(const std::string& field,
                            const std::string& file_name,
                            const std::string& bytes,
                            const core::Model& model,
                            const std::string& temp_root,
                            const UploadRules& rules = {},
                            bool retarget = false,
                            const std::vector<animator::MappingEntry>& mapping = {},
                            const std::vector<UploadResource>& resources = {});

/// The correspondence retargeting would guess for an uploaded motion file (.bvh, .glb, .gltf,
/// .fbx, .dae) onto `model`, for the user to edit: {"source_convention", "target_convention",
/// "same_skeleton": bool, "joints": [{"source": joint, "target": link | null}, ...] (every moving
/// joint of the clip, file order), "links": [every moving link of the character]}.
/// Caps and errors as for clip_from_upload. @throws UploadError
nlohmann::json clip_correspondence(const std::string& field,
                                   const std::string& file_name,
                                   const std::string& bytes,
                                   const core::Model& model,
                                   const std::string& temp_root,
                                   const UploadRules& rules = {},
                                   const std::vector<UploadResource>& resources = {});

}  // namespace server
