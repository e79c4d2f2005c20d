#include "io/model_file.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "io/character_json.hpp"
#include "io/urdf.hpp"

namespace io {

using namespace core;  // io reads and writes core's types

LoadResult load_model_file(const std::string& path, const LoadOptions& options) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".urdf") return load_urdf_file(path, options);
  // a character file says how its root attaches, so the root option does not apply
  if (ext == ".json") return load_character_json_file(path);
  throw ModelError(
      {path + ": unknown file type '" + ext + "' (rule: character files end in .urdf or .json)"});
}

}  // namespace io
