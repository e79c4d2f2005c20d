// Motion subspaces S_i of the joint types, in the child (link) frame: a revolute joint moves
// along [a; 0], a prismatic joint along [0; a], a spherical joint along [E; 0], a free joint
// along the identity. S is constant in the link frame for all of them (Ṡ = 0).
#pragma once

#include "core/model.hpp"
#include "core/spatial.hpp"

namespace core {

/// Column d of S_i.
inline Motion subspace_column(const Model& model, int i, int d) {
  switch (model.joint_type[i]) {
    case JointType::kRevolute:
      return {model.axis[i], Vector3::Zero()};
    case JointType::kPrismatic:
      return {Vector3::Zero(), model.axis[i]};
    case JointType::kSpherical:
      return {Vector3::Unit(d), Vector3::Zero()};
    case JointType::kFree:
      return d < 3 ? Motion{Vector3::Unit(d), Vector3::Zero()}
                   : Motion{Vector3::Zero(), Vector3::Unit(d - 3)};
    case JointType::kFixed:
      break;
  }
  return Motion::Zero();
}

/// Writes S_iᵀ f to out[0 .. nv_i).
template <typename Out>
inline void subspace_transpose(const Model& model, int i, const Force& f, Out&& out) {
  switch (model.joint_type[i]) {
    case JointType::kFixed:
      break;
    case JointType::kRevolute:
      out[0] = model.axis[i].dot(f.angular);
      break;
    case JointType::kPrismatic:
      out[0] = model.axis[i].dot(f.linear);
      break;
    case JointType::kSpherical:
      for (int k = 0; k < 3; ++k) out[k] = f.angular[k];
      break;
    case JointType::kFree:
      for (int k = 0; k < 3; ++k) {
        out[k] = f.angular[k];
        out[k + 3] = f.linear[k];
      }
      break;
  }
}

}  // namespace core
