#include "cli/marker_set_file.hpp"

#include <iostream>

#include "cli/json_fields.hpp"

namespace cli {

ik::MarkerSet read_marker_set_file(const std::string& path, const core::Model& model) {
  const nlohmann::json doc = read_json_file(path);
  try {
    return animator::parse_marker_set(
        doc, model, [](const std::string& w) { std::cerr << "warning: " << w << "\n"; });
  } catch (const animator::MarkerSetError& e) {
    throw RequestError(path + ": " + e.what());
  }
}

}  // namespace cli
