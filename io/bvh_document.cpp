#include "io/bvh_document.hpp"

#include <algorithm>
#include <numbers>

#include "io/bvh_euler.hpp"
#include "io/bvh_text.hpp"

namespace io {

const char* to_string(BvhChannel c) {
  switch (c) {
    case BvhChannel::kXposition:
      return "Xposition";
    case BvhChannel::kYposition:
      return "Yposition";
    case BvhChannel::kZposition:
      return "Zposition";
    case BvhChannel::kXrotation:
      return "Xrotation";
    case BvhChannel::kYrotation:
      return "Yrotation";
    case BvhChannel::kZrotation:
      return "Zrotation";
  }
  return "?";
}

int BvhDocument::joint_count() const {
  return static_cast<int>(
      std::count_if(nodes.begin(), nodes.end(), [](const BvhNode& n) { return !n.is_end_site(); }));
}

Matrix3 bvh_joint_rotation(const BvhNode& node, const double* frame_values) {
  Matrix3 R = Matrix3::Identity();
  for (std::size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (is_rotation(c))
      R = R * elementary_rotation(channel_axis(c), frame_values[k] * bvh_detail::kDegree);
  }
  return R;
}

Vector3 bvh_joint_translation(const BvhNode& node, const double* frame_values) {
  Vector3 p = node.offset;
  for (std::size_t k = 0; k < node.channels.size(); ++k) {
    const BvhChannel c = node.channels[k];
    if (!is_rotation(c)) p[channel_axis(c)] = frame_values[k];
  }
  return p;
}

std::vector<Transform> bvh_world_poses(const BvhDocument& doc, int frame) {
  std::vector<Transform> X(doc.nodes.size());
  const double* values = frame >= 0 ? doc.frame(frame) : nullptr;
  for (std::size_t n = 0; n < doc.nodes.size(); ++n) {
    const BvhNode& node = doc.nodes[n];
    Transform local = Transform::from_translation(node.offset);
    if (values && !node.is_end_site()) {
      const double* v = values + node.first_value;
      local.p = bvh_joint_translation(node, v);
      local.R = bvh_joint_rotation(node, v);
    }
    X[n] = node.parent < 0 ? local : X[node.parent] * local;
  }
  return X;
}

BvhExtent bvh_rest_extent(const BvhDocument& doc) {
  if (doc.nodes.empty()) return {};
  const std::vector<Transform> X = bvh_world_poses(doc, -1);
  Vector3 lo = X[0].p, hi = X[0].p;
  for (const Transform& x : X) {
    lo = lo.cwiseMin(x.p);
    hi = hi.cwiseMax(x.p);
  }
  const Vector3 size = hi - lo;
  return {size.y(), size.maxCoeff()};
}

}  // namespace io
