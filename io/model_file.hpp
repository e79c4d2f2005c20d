// Loading character files of any supported kind into a Model.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "core/model_builder.hpp"
#include "io/core_names.hpp"

namespace io {

/// How the root link attaches to the world when the file does not say (URDF has no way to).
enum class RootJoint { kAsInFile, kFixed, kFree };

struct LoadOptions {
  RootJoint root = RootJoint::kAsInFile;
};

/// A loaded model and what the loader could not represent (named, never silently dropped).
struct LoadResult {
  std::shared_ptr<const Model> model;
  std::vector<std::string> warnings;
};

/// Loads a character by extension: .urdf (io/urdf.hpp) or .json (io/character_json.hpp;
/// the file says how its root attaches, so `options` applies to URDF only).
/// @throws ModelError naming the file (and line or field) and the rule broken
LoadResult load_model_file(const std::string& path, const LoadOptions& options = {});

}  // namespace io
