// Lookups on a C3D trial (io/c3d.hpp).
#include <stdexcept>

#include "io/c3d.hpp"

namespace io {

namespace {

std::size_t index_of(const C3dTrial& t, int frame, int point) {
  if (frame < 0 || frame >= t.frames || point < 0 || point >= t.point_count()) {
    throw std::out_of_range("C3dTrial: sample (" + std::to_string(frame) + ", " +
                            std::to_string(point) + ") outside " + std::to_string(t.frames) +
                            " frames x " + std::to_string(t.point_count()) + " points");
  }
  return static_cast<std::size_t>(frame) * t.labels.size() + static_cast<std::size_t>(point);
}

}  // namespace

const Eigen::Vector3d& C3dTrial::position(int frame, int point) const {
  return positions[index_of(*this, frame, point)];
}

bool C3dTrial::is_present(int frame, int point) const {
  return present[index_of(*this, frame, point)] != 0;
}

int C3dTrial::find(std::string_view label) const {
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i] == label) return static_cast<int>(i);
  }
  // `Male:LFHD` finds LFHD of subject Male
  if (subject.empty() || label.size() <= subject.size() + 1 ||
      label.substr(0, subject.size()) != subject || label[subject.size()] != ':') {
    return -1;
  }
  return find(label.substr(subject.size() + 1));
}

double C3dTrial::missing_fraction() const {
  if (present.empty()) return 0;
  std::size_t missing = 0;
  for (std::uint8_t p : present) missing += p == 0;
  return static_cast<double>(missing) / static_cast<double>(present.size());
}

}  // namespace io
