#include "io/bundled_characters.hpp"

#include <cstdlib>
#include <filesystem>

#include "core/human_figure.hpp"

#ifndef PINDRAG_CHARACTERS_DIR
#define PINDRAG_CHARACTERS_DIR "characters"
#endif

namespace io {

using namespace core;  // io reads and writes core's types

std::vector<BundledCharacter> bundled_characters() {
  return {
      {"human48",
       "human figure, 48 DOF: spherical waist, chest, neck, shoulders, wrists, hips, ankles"},
      {"human34", "human figure, 34 DOF (HeiMan-like, Felis et al.)"},
      {"arm7", "7-DOF fixed-base arm"},
      {"manipulator5", "5-DOF heavy hydraulic manipulator (Newton-Euler example)"},
  };
}

std::string characters_dir() {
  if (const char* e = std::getenv("PINDRAG_CHARACTERS_DIR"); e && *e) return e;
  return PINDRAG_CHARACTERS_DIR;
}

LoadResult load_character(const std::string& name_or_path, const LoadOptions& options) {
  if (name_or_path == "human48" || name_or_path == "human34") {
    HumanFigureOptions o;
    o.dof = name_or_path == "human48" ? 48 : 34;
    return {build_human_figure(o), {}};
  }
  if (name_or_path == "arm7" || name_or_path == "manipulator5") {
    return load_model_file(characters_dir() + "/" + name_or_path + ".urdf", options);
  }
  if (!std::filesystem::exists(name_or_path)) {
    std::string names;
    for (const auto& c : bundled_characters()) names += (names.empty() ? "" : ", ") + c.name;
    throw ModelError({"'" + name_or_path + "' is neither a bundled character (" + names +
                      ") nor an existing file"});
  }
  return load_model_file(name_or_path, options);
}

}  // namespace io
