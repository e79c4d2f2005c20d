#include "animator/floor_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/configuration.hpp"

namespace animator {

namespace {

// the floor: the plane y = 0, its normal up
const core::Vector3 kUp{0, 1, 0};

// the point of a shape lowest along the floor's normal, in the world
core::Vector3 lowest_point(const sim::LinkShape& s, const core::Transform& X_WS) {
  switch (s.kind) {
    case sim::LinkShape::Kind::kSphere:
      return X_WS.p - s.radius * kUp;
    case sim::LinkShape::Kind::kCapsule: {
      const core::Vector3 axis = X_WS.R.col(2);
      const double down = axis.dot(kUp) > 0 ? -1.0 : 1.0;  // the end further down
      return X_WS.p + down * s.half_length * axis - s.radius * kUp;
    }
    case sim::LinkShape::Kind::kBox: {
      // the corner whose every axis points down: Σ −sign(n · a_k) h_k a_k
      core::Vector3 p = X_WS.p;
      for (int k = 0; k < 3; ++k) {
        const core::Vector3 a = X_WS.R.col(k);
        p -= (a.dot(kUp) > 0 ? 1.0 : -1.0) * s.half_extents[k] * a;
      }
      return p;
    }
  }
  return X_WS.p;
}

}  // namespace

FloorContacts::FloorContacts(const core::Model& model)
    : model_(model),
      shapes_(sim::build_body_shapes(model, core::neutral_configuration(model))),
      movable_(model.njoints, 0),
      held_(model.njoints, 0),
      floor_(model.njoints, 0.0) {
  for (int i = 1; i < model.njoints; ++i) {
    movable_[i] = movable_[model.parent[i]] || model.joint_type[i] != core::JointType::kFixed;
  }
}

FloorContacts::Lowest FloorContacts::lowest(const core::Data& data, int link) const {
  Lowest out{std::numeric_limits<double>::infinity(), core::Vector3::Zero(), false};
  for (const sim::LinkShape& s : shapes_.shapes[link]) {
    const core::Vector3 p = lowest_point(s, data.X_W[link] * s.X_LinkShape);
    if (p.y() < out.height) out = {p.y(), p, s.kind == sim::LinkShape::Kind::kBox};
  }
  return out;
}

double FloorContacts::height(const core::Data& data, int link) const {
  return lowest(data, link).height;
}

void FloorContacts::hold(const core::Data& data, int link, const Lowest& low, double lift) {
  const core::Transform& X_WL = data.X_W[link];
  Pin pin;
  pin.link = link;
  if (low.box) {
    pin.mode = ik::TaskMode::kPose;
    pin.target_W = X_WL.p + lift * kUp;
    pin.target_R_W = core::Quaternion(X_WL.R);
  } else {
    pin.mode = ik::TaskMode::kPosition;
    pin.p_LinkPoint = X_WL.R.transpose() * (low.point_W - X_WL.p);
    pin.target_W = low.point_W + lift * kUp;
  }
  pins_.push_back(pin);
  held_[link] = 1;
}

void FloorContacts::begin(const core::Data& data, const std::vector<char>& excluded) {
  clear();
  std::vector<char> resting(model_.njoints, 0);
  for (int i = 1; i < model_.njoints; ++i) {
    if (!movable_[i]) continue;
    const Lowest low = lowest(data, i);
    floor_[i] = std::min(0.0, low.height);
    resting[i] = low.height <= kRestingReach;
    if (resting[i] && !resting[model_.parent[i]] && !excluded[i]) hold(data, i, low, 0.0);
  }
}

bool FloorContacts::catch_penetrations(const core::Data& data, const std::vector<char>& excluded) {
  bool added = false;
  for (int i = 1; i < model_.njoints; ++i) {
    if (!movable_[i] || held_[i] || excluded[i]) continue;
    const Lowest low = lowest(data, i);
    if (low.height < floor_[i]) {
      hold(data, i, low, floor_[i] - low.height);  // back to the floor, or where it began
      added = true;
    }
  }
  return added;
}

void FloorContacts::clear() {
  pins_.clear();
  std::fill(held_.begin(), held_.end(), 0);
  std::fill(floor_.begin(), floor_.end(), 0.0);
}

double FloorContacts::depth(const core::Data& data, int link) const {
  return floor_[link] - lowest(data, link).height;
}

}  // namespace animator
