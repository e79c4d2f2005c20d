// The characters that ship with pindrag, by name, and loading "a name or a file".
#pragma once

#include <string>
#include <vector>

#include "io/core_names.hpp"
#include "io/model_file.hpp"

namespace io {

struct BundledCharacter {
  std::string name;
  std::string description;
};

/// human48 and human34 (generated), arm7 and manipulator5 (files in the characters folder).
std::vector<BundledCharacter> bundled_characters();

/// The folder of the bundled character files: $PINDRAG_CHARACTERS_DIR, else the source tree's
/// characters/ folder recorded at build time.
std::string characters_dir();

/// A bundled character by name, else a character file by path (io/model_file.hpp).
/// @throws ModelError naming the name or file and what is wrong
LoadResult load_character(const std::string& name_or_path, const LoadOptions& options = {});

}  // namespace io
