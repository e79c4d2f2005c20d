// A pin held by the posing solver: a point on a link kept at a world target.
#pragma once

#include "core/spatial.hpp"
#include "ik/task.hpp"

namespace animator {

struct Pin {
  int link = 0;
  ik::TaskMode mode = ik::TaskMode::kPosition;
  core::Vector3 p_LinkPoint = core::Vector3::Zero();  // the pinned point, link frame
  core::Vector3 target_W = core::Vector3::Zero();
  core::Quaternion target_R_W = core::Quaternion::Identity();

  bool operator==(const Pin& o) const {
    return link == o.link && mode == o.mode && p_LinkPoint == o.p_LinkPoint &&
           target_W == o.target_W && target_R_W.coeffs() == o.target_R_W.coeffs();
  }

  /// The solver's task for this pin (the solver's default gain and weight).
  ik::LinkTask task() const {
    return ik::LinkTask{.role = ik::kPin,
                        .link = link,
                        .p_LinkPoint = p_LinkPoint,
                        .target_W = target_W,
                        .target_R_W = target_R_W,
                        .mode = mode};
  }
};

}  // namespace animator
