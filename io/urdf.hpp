// URDF import through urdfdom (urdf::parseURDF), with tinyxml2 for what urdfdom drops.
//
// Supported: revolute, continuous (revolute without range), prismatic, fixed and floating
// (free) joints; inertials; limits; box, sphere, cylinder and mesh geometry, plus Bullet's
// non-standard <capsule radius length> (with a warning that names it). Everything else the file
// holds (mimic, <dynamics>, <safety_controller>, <calibration>, <transmission>, <gazebo>, unknown
// elements, materials) is named in LoadResult::warnings; a planar or unknown joint type is an
// error, and so are two joints (or two links) of the same name, a link with two parents, a cycle
// and elements nested deeper than kMaxUrdfDepth. Every ModelError line starts with the source
// name.
//
// Frames: URDF is Z-up (x forward, y left); pindrag is Y-up with characters facing +Z and +X
// the character's left. Every link frame is re-expressed with C = urdf_to_y_up() at import (see
// urdf_import.cpp), so the world pose of every link is (C R_urdf Cᵀ, C p_urdf); a shape keeps its
// own local axes (mesh vertices and cylinder or capsule z axes stay as authored).
//
// Meshes: package://PKG/rest resolves in the nearest ancestor folder of the URDF named PKG;
// relative paths resolve against the URDF's folder; file:// and absolute paths are accepted only
// inside the model folder. The model folder (Model::source_dir) is the package folder when
// package:// is used, else the URDF's folder. A mesh that escapes it or does not exist is dropped
// with a warning; Geometry::mesh is stored relative to Model::source_dir.
//
// Thread safety: loads may run on any thread; the urdfdom parse itself is serialized, because
// urdfdom reports through console_bridge's process-wide output handler.
#pragma once

#include <cstddef>
#include <string>

#include "core/spatial.hpp"
#include "io/core_names.hpp"
#include "io/model_file.hpp"

namespace io {

/// Largest URDF accepted (bytes); larger files are refused before parsing.
constexpr std::size_t kMaxUrdfBytes = std::size_t{64} << 20;
/// Most warnings listed for one file; the rest are counted in a last warning.
constexpr std::size_t kMaxUrdfWarnings = 1000;
/// Deepest element nesting accepted (<robot> alone is 1; real URDFs stay under 10). Deeper text
/// is refused before any XML parser sees it: urdfdom's parser, TinyXML 1, recurses once per
/// level without a limit, and about 37,000 levels (120 KB) overflow an 8 MB stack.
constexpr int kMaxUrdfDepth = 64;
/// Most attributes on one element (URDF elements have at most 6). More are refused before any
/// XML parser sees them: both parsers check each attribute against all earlier ones of its
/// element, and 200,000 attributes (2 MB) take minutes.
constexpr int kMaxUrdfAttributes = 64;

/// Change of basis from URDF (Z-up) to pindrag (Y-up) coordinates: v_ours = C v_urdf with
/// C = [[0,1,0],[0,0,1],[1,0,0]] (ROS x forward → our +Z, y left → our +X, z up → our +Y).
Matrix3 urdf_to_y_up();

/// Loads a URDF file. Meshes resolve relative to the file's folder (see above).
/// @throws ModelError naming the file (and link, joint or field) and the rule broken
LoadResult load_urdf_file(const std::string& path, const LoadOptions& options = {});

/// Loads URDF text. `source_name` prefixes every message; `base_dir` is the folder the URDF
/// lives in (meshes resolve against it; when empty every mesh is dropped with a warning).
/// @throws ModelError naming the source (and link, joint or field) and the rule broken
LoadResult load_urdf_string(const std::string& xml,
                            const std::string& source_name,
                            const std::string& base_dir,
                            const LoadOptions& options = {});

}  // namespace io
