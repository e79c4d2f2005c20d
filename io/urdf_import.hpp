// The URDF loader's import (internal to io/urdf*.cpp): urdfdom's model, read in the file's Z-up
// frame, becomes a core::Model in pindrag's Y-up frame through core::ModelBuilder. The frame
// change is in urdf_import.cpp; the root rules (a massless "world" link is the world, the root
// joint follows LoadOptions) are in io/urdf.hpp.
#pragma once

#include <urdf_model/model.h>

#include <string>
#include <vector>

#include "io/model_file.hpp"
#include "io/urdf_scan.hpp"

namespace io::urdf_internal {

/// Throws a ModelError whose violations are `lines`, each prefixed by "<source>: ".
[[noreturn]] void fail(const std::string& source, const std::vector<std::string>& lines);

/// The model urdfdom read, imported: links in document order, meshes resolved against
/// `base_dir` (see MeshResolver). `warnings` (without the source prefix) come first in the
/// result, then the import's own; all are prefixed by "<source>: " and capped at kMaxUrdfWarnings.
/// @throws ModelError naming the source when the model cannot be imported or fails finalize()
LoadResult import_urdf(const urdf::ModelInterface& model,
                       const Scan& scan,
                       const std::string& source,
                       const std::string& base_dir,
                       const LoadOptions& options,
                       std::vector<std::string> warnings);

}  // namespace io::urdf_internal
