// Uploaded files turned into characters and clips. The bytes are written to a private temporary
// folder (mode 0700) under a name the server makes, loaded with core/io (assimp formats in a
// sandboxed child process), and removed; a client never names a path.
#pragma once

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "animator/session.hpp"
#include "core/clip.hpp"

namespace server {

/// A file the server will not take; what() names the field and the rule. Maps to 4xx.
class UploadError : public std::runtime_error {
 public:
  UploadError(int http_status, const std::string& message)
      : std::runtime_error(message), status(http_status) {}
  int status;
};

/// A new session named `name` from a character file on disk chosen by the operator (by
/// extension: .urdf, .json, .bvh, .glb, .gltf, .fbx, .dae; a BVH or an animated skinned file also
/// brings its first clip). @throws core::ModelError or std::runtime_error naming the file
std::unique_ptr<animator::Session> session_from_file(const std::string& path,
                                                     const std::string& name);

/// A new session from an uploaded character file (.urdf, .json, .bvh, .glb, .gltf, .fbx, .dae);
/// a BVH or an animated glTF/FBX/COLLADA file also brings its first clip.
/// `field` names the form field in messages. @throws UploadError
std::unique_ptr<animator::Session> session_from_upload(const std::string& field,
                                                       const std::string& file_name,
                                                       const std::string& bytes,
                                                       const std::string& temp_root);

/// The first clip of an uploaded motion file (.bvh, .glb, .gltf, .fbx, .dae). The clip must fit
/// `model` (same links, same joint types), else UploadError 422. @throws UploadError
core::Clip clip_from_upload(const std::string& field,
                            const std::string& file_name,
                            const std::string& bytes,
                            const core::Model& model,
                            const std::string& temp_root);

}  // namespace server
