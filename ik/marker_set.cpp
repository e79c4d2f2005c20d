#include "ik/marker_set.hpp"

#include <cmath>

namespace ik {

int MarkerSet::find(std::string_view name) const {
  for (int i = 0; i < size(); ++i) {
    if (markers[i].name == name) return i;
  }
  return -1;
}

std::string check_marker_set(const core::Model& model, const MarkerSet& set) {
  for (int i = 0; i < set.size(); ++i) {
    const Marker& m = set.markers[i];
    const std::string who = "marker '" + m.name + "'";
    if (m.name.empty()) return "marker " + std::to_string(i) + ": empty name";
    if (m.link < 1 || m.link >= model.njoints) return who + ": link index out of range";
    if (!m.offset.allFinite()) return who + ": offset is not finite";
    if (!std::isfinite(m.weight) || m.weight < 0) return who + ": weight must be finite and >= 0";
    if (set.find(m.name) != i) return who + ": name given twice";
  }
  return {};
}

}  // namespace ik
