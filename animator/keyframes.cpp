#include "animator/keyframes.hpp"

#include <algorithm>
#include <cmath>

#include "core/clip.hpp"
#include "core/configuration.hpp"

namespace animator {

using core::JointType;
using core::Quaternion;

const char* to_string(Interpolation i) {
  switch (i) {
    case Interpolation::kStep:
      return "step";
    case Interpolation::kLinear:
      return "linear";
    case Interpolation::kSmooth:
      return "smooth";
  }
  return "?";
}

std::optional<Interpolation> interpolation_from_string(std::string_view s) {
  for (Interpolation i : {Interpolation::kStep, Interpolation::kLinear, Interpolation::kSmooth}) {
    if (s == to_string(i)) return i;
  }
  return std::nullopt;
}

int KeyTrack::insert(Keyframe key) {
  const int existing = find(key.time, 1e-9);
  if (existing >= 0) {
    keys_[existing] = std::move(key);
    return existing;
  }
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), key.time,
                                   [](const Keyframe& k, double t) { return k.time < t; });
  const int index = static_cast<int>(it - keys_.begin());
  keys_.insert(it, std::move(key));
  return index;
}

bool KeyTrack::remove(int index) {
  if (index < 0 || index >= static_cast<int>(keys_.size())) return false;
  keys_.erase(keys_.begin() + index);
  return true;
}

int KeyTrack::move(int index, double time) {
  if (index < 0 || index >= static_cast<int>(keys_.size())) return -1;
  Keyframe k = keys_[index];
  keys_.erase(keys_.begin() + index);
  k.time = time;
  return insert(std::move(k));
}

int KeyTrack::find(double time, double tolerance) const {
  for (size_t i = 0; i < keys_.size(); ++i) {
    if (std::abs(keys_[i].time - time) <= tolerance) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// cubic Hermite between p1 and p2 with Catmull–Rom tangents from p0 and p3 (times t0..t3)
double hermite(double p0,
               double p1,
               double p2,
               double p3,
               double t0,
               double t1,
               double t2,
               double t3,
               double s) {
  const double m1 = t2 > t0 ? (p2 - p0) / (t2 - t0) * (t2 - t1) : p2 - p1;
  const double m2 = t3 > t1 ? (p3 - p1) / (t3 - t1) * (t2 - t1) : p2 - p1;
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * p1 + (s3 - 2 * s2 + s) * m1 + (-2 * s3 + 3 * s2) * p2 +
         (s3 - s2) * m2;
}

Quaternion same_hemisphere(const Quaternion& ref, Quaternion q) {
  if (ref.dot(q) < 0) q.coeffs() *= -1;
  return q;
}

// squad control point for q_i with neighbours (Shoemake): s_i = q_i exp(−(log(q_i⁻¹q_{i+1}) +
// log(q_i⁻¹q_{i−1})) / 4)
Quaternion squad_control(const Quaternion& prev, const Quaternion& q, const Quaternion& next) {
  const core::Vector3 a = core::quaternion_log(q.conjugate() * next);
  const core::Vector3 b = core::quaternion_log(q.conjugate() * prev);
  // quaternion_log returns the rotation vector (angle·axis) = 2 log(q); the squad formula uses
  // log(q) = half of it
  return q * core::quaternion_exp(-(a + b) / 4.0);
}

}  // namespace

void KeyTrack::sample(const core::Model& model, double t, Eigen::VectorXd& q_out) const {
  if (keys_.empty()) {
    q_out = core::neutral_configuration(model);
    return;
  }
  if (t <= keys_.front().time) {
    q_out = keys_.front().q;
    return;
  }
  if (t >= keys_.back().time) {
    q_out = keys_.back().q;
    return;
  }
  const auto it = std::upper_bound(keys_.begin(), keys_.end(), t,
                                   [](double tt, const Keyframe& k) { return tt < k.time; });
  const int i2 = static_cast<int>(it - keys_.begin());
  const int i1 = i2 - 1;
  const Keyframe& k1 = keys_[i1];
  const Keyframe& k2 = keys_[i2];
  if (t == k1.time || k1.interpolation == Interpolation::kStep) {
    q_out = k1.q;
    return;
  }
  const double s = (t - k1.time) / (k2.time - k1.time);
  if (k1.interpolation == Interpolation::kLinear) {
    core::interpolate(model, k1.q, k2.q, s, q_out);
    return;
  }
  // smooth: Catmull–Rom on scalars, squad on rotations
  const Keyframe& k0 = keys_[std::max(0, i1 - 1)];
  const Keyframe& k3 = keys_[std::min(static_cast<int>(keys_.size()) - 1, i2 + 1)];
  q_out.resize(model.nq);
  for (int j = 1; j < model.njoints; ++j) {
    const int iq = model.idx_q[j];
    auto scalar = [&](int c) {
      q_out[c] = hermite(k0.q[c], k1.q[c], k2.q[c], k3.q[c], k0.time, k1.time, k2.time, k3.time, s);
    };
    auto rotation = [&](int c) {
      const Quaternion q1 = core::quaternion_at(k1.q, c);
      const Quaternion q0 = same_hemisphere(q1, core::quaternion_at(k0.q, c));
      const Quaternion q2 = same_hemisphere(q1, core::quaternion_at(k2.q, c));
      const Quaternion q3 = same_hemisphere(q2, core::quaternion_at(k3.q, c));
      const Quaternion a = squad_control(q0, q1, q2);
      const Quaternion b = squad_control(q1, q2, q3);
      // squad(q1, q2, a, b; s) = slerp(slerp(q1, q2, s), slerp(a, b, s), 2s(1 − s))
      const Quaternion r = q1.slerp(s, q2).slerp(2 * s * (1 - s), a.slerp(s, b));
      core::set_quaternion_at(q_out, c, r.normalized());
    };
    switch (model.joint_type[j]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        scalar(iq);
        break;
      case JointType::kSpherical:
        rotation(iq);
        break;
      case JointType::kFree:
        for (int c = 0; c < 3; ++c) scalar(iq + c);
        rotation(iq + 3);
        break;
    }
  }
}

}  // namespace animator
