// The files an uploaded .gltf, .glb, .fbx or .dae references (a .gltf's .bin buffers, images),
// sent beside it: their names and sizes checked, and the buffers a .gltf needs checked to be
// among them, before anything is written or imported.
#pragma once

#include <string>
#include <vector>

namespace server {

struct UploadCaps;

/// One file sent with a character or clip file (form field "resource"), by its file name.
struct UploadResource {
  std::string name;
  std::string bytes;
};

/// A resource and the name it is stored under, beside the upload.
struct StoredResource {
  std::string name;
  const UploadResource* resource;
};

/// At most this many resources come with one file.
inline constexpr int kMaxUploadResources = 64;

/// Checks the resources sent with the file `shown` (extension `ext`, contents `bytes`), read
/// from form field `field`: only a .gltf, .glb, .fbx or .dae references other files; at most
/// kMaxUploadResources, each a plain file name (no folder, not hidden, no control characters,
/// not "upload" + ext, which the upload itself is stored as) given once; the file and its
/// resources together within its type's upload cap; and every buffer a .gltf names by a relative
/// URI among them.
/// Returns what to store beside the upload: each resource by its name, and a buffer whose URI
/// is percent-encoded ("my%20skin.bin") under that URI as well (assimp does not decode URIs).
/// @throws UploadError (400 for a malformed request, 413 over the cap, 422 for a buffer that
///         was not sent, naming it)
std::vector<StoredResource> check_upload_resources(const std::string& field,
                                                   const std::string& shown,
                                                   const std::string& ext,
                                                   const std::string& bytes,
                                                   const std::vector<UploadResource>& resources,
                                                   const UploadCaps& caps);

}  // namespace server
