// Mesh paths of a URDF (internal to io/urdf*.cpp): package://PKG/rest resolves in the nearest
// ancestor folder of the URDF named PKG; relative paths resolve against the URDF's folder;
// file:// and absolute paths are accepted only inside the model folder. The model folder is the
// package folder of the first package:// URI that resolves, else the URDF's folder.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace io::urdf_internal {

class MeshResolver {
 public:
  /// base_dir: the URDF's folder (may be empty: then no mesh resolves); uris: every mesh URI of
  /// the file in document order
  MeshResolver(const std::string& base_dir, const std::vector<std::string>& uris);

  /// The model folder (empty without a base folder).
  const std::filesystem::path& root() const { return root_; }

  /// Path of the mesh relative to root(), or nullopt with the reason in `why` (a missing file, a
  /// path outside the model folder, directly or through a symbolic link, an unknown scheme).
  std::optional<std::string> resolve(const std::string& uri, std::string& why) const;

 private:
  std::filesystem::path urdf_dir_;
  std::filesystem::path root_;
};

}  // namespace io::urdf_internal
