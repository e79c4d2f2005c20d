// Virtual markers on a character's links (Felis et al., eq. 13: r^M, the model's markers): a
// marker set maps marker names to a link and an offset in that link's frame. Offsets may be left
// out of a marker set file; they are then estimated from a static range (ik/marker_calibration).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/model.hpp"

namespace ik {

struct Marker {
  std::string name;                              // label as in the motion-capture file
  int link = 0;                                  // link the marker rides on (1 … njoints-1)
  core::Vector3 offset = core::Vector3::Zero();  // p_LinkMarker: the marker in the link frame (m)
  bool offset_given = true;  // false: to be estimated (the offset holds the first guess)
  double weight = 1.0;       // weight of its rows in the least-squares fit
};

struct MarkerSet {
  std::vector<Marker> markers;

  int size() const { return static_cast<int>(markers.size()); }
  /// Index of the marker called `name`, or -1.
  int find(std::string_view name) const;
};

/// Empty when every marker names a link of `model` and has a finite offset and a finite weight
/// >= 0 and the names are unique; else a message naming the first bad marker.
std::string check_marker_set(const core::Model& model, const MarkerSet& set);

}  // namespace ik
