// The native character format: JSON that carries everything a core::Model holds and URDF cannot
// (spherical joints with swing–twist ranges, standard orientations, IK weights and gains,
// capsules, display names, gravity, the model name). docs/character-format.md is the reference.
//
// Round trip: load(write(m)) == m exactly (Model::operator==) for every model ModelBuilder
// builds, and write(load(write(m))) == write(m) byte for byte. Placements and shape poses are
// written as 3×3 rotation matrices (a quaternion would not reproduce the matrix bits), doubles in
// shortest round-trip form, and the inertia about the COM is chosen so that the builder's
// parallel-axis shift reproduces the stored spatial inertia bit for bit.
//
// Bad input: every ModelError line starts with the source name, then the JSON pointer of the
// field (or line and column for a syntax error) and the rule broken, e.g.
//   human.json: /links/3/inertial/mass: expected a number, got a string
// Unknown keys are warnings naming their pointer. Files above kMaxCharacterJsonBytes, more than
// kMaxLinks links, nesting deeper than kMaxJsonDepth, more than kMaxJsonValues values and more
// range triangles than the format allows are refused before a Model is built.
#pragma once

#include <cstddef>
#include <string>

#include "core/model.hpp"
#include "io/core_names.hpp"
#include "io/json_parse.hpp"
#include "io/model_file.hpp"

namespace io {

/// Largest character file accepted (bytes); larger files are refused before reading. Nesting and
/// value count are capped at kMaxJsonDepth and kMaxJsonValues (io/json_parse.hpp).
constexpr std::size_t kMaxCharacterJsonBytes = std::size_t{64} << 20;
/// The value of the "format" key and the version this build reads and writes.
inline constexpr const char* kCharacterFormat = "pindrag-character";
constexpr int kCharacterFormatVersion = 1;

/// Loads a character file. Meshes resolve against the file's folder (Model::source_dir).
/// @throws ModelError naming the file, the JSON pointer (or line and column) and the rule broken
LoadResult load_character_json_file(const std::string& path);

/// Loads character JSON text. `source_name` prefixes every message and warning; `base_dir` is the
/// folder meshes resolve against (stored as Model::source_dir; may be empty).
/// @throws ModelError naming the source, the JSON pointer (or line and column) and the rule broken
LoadResult load_character_json_string(const std::string& text,
                                      const std::string& source_name,
                                      const std::string& base_dir);

/// Writes a model as character JSON (UTF-8, 2-space indentation, ends with a newline).
/// @throws std::invalid_argument when the model holds what JSON cannot carry: a name that is not
///         valid UTF-8, or a joint limit that is +inf as a lower or -inf as an upper bound
std::string write_character_json(const Model& model);

/// Writes write_character_json(model) to `path` atomically: a temporary file in the same folder,
/// fsync, rename over `path`, fsync of the folder. A reader sees the old file or the new one.
/// @throws std::system_error (or std::invalid_argument from the writer) naming the path
void save_character_json_file(const Model& model, const std::string& path);

}  // namespace io
