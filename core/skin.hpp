// A skinned mesh bound to a character's links (linear blend skinning), as imported from glTF,
// FBX or DAE and exported to glTF.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/spatial.hpp"

namespace core {

struct SkinnedMesh {
  std::string name;
  std::vector<Eigen::Vector3f> positions;     // bind pose, world frame of the model
  std::vector<Eigen::Vector3f> normals;       // empty or one per position
  std::vector<std::array<int, 3>> triangles;  // indices into positions
  std::vector<std::array<int, 4>> joints;     // per vertex: indices into `bones`
  std::vector<std::array<float, 4>> weights;  // per vertex, summing to 1
  std::vector<int> bones;                     // link index of each skin joint
  std::vector<Transform> inverse_bind;        // per bone: world → bone frame at bind pose
  Eigen::Vector4f base_color = Eigen::Vector4f(0.8f, 0.8f, 0.8f, 1.0f);

  bool empty() const { return positions.empty(); }
};

}  // namespace core
