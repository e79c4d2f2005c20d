#include "animator/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

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

std::shared_ptr<const KeyTrack::Keys> KeyTrack::empty_keys() {
  static const auto kEmpty = std::make_shared<const Keys>();
  return kEmpty;
}

namespace {

bool before_time(const Keyframe& k, double t) { return k.time < t; }

}  // namespace

int KeyTrack::insert(Keyframe key) {
  auto keys = std::make_shared<Keys>(*keys_);
  int index = find(key.time, 1e-9);
  if (index >= 0) {
    (*keys)[index] = std::move(key);
  } else {
    const auto it = std::lower_bound(keys->begin(), keys->end(), key.time, before_time);
    index = static_cast<int>(it - keys->begin());
    keys->insert(it, std::move(key));
  }
  keys_ = std::move(keys);
  return index;
}

bool KeyTrack::remove(int index) {
  if (index < 0 || index >= size()) return false;
  auto keys = std::make_shared<Keys>(*keys_);
  keys->erase(keys->begin() + index);
  keys_ = std::move(keys);
  return true;
}

int KeyTrack::move(int index, double time) {
  if (index < 0 || index >= size()) return -1;
  Keyframe k = (*keys_)[index];
  remove(index);
  k.time = time;
  return insert(std::move(k));
}

int KeyTrack::find(double time, double tolerance) const {
  // keys are sorted and more than 1e-9 s apart: look around the first key not before time − tol
  const Keys& keys = *keys_;
  const auto it = std::lower_bound(keys.begin(), keys.end(), time - tolerance, before_time);
  for (auto k = it; k != keys.end() && k->time <= time + tolerance; ++k) {
    if (std::abs(k->time - time) <= tolerance) return static_cast<int>(k - keys.begin());
  }
  return -1;
}

void KeyTrack::apply(const KeyChange& change, bool forward) {
  const std::vector<Keyframe>& out = forward ? change.removed : change.added;
  const std::vector<Keyframe>& in = forward ? change.added : change.removed;
  if (out.empty() && in.empty()) return;
  auto keys = std::make_shared<Keys>();
  keys->reserve(keys_->size() + in.size());
  // one merge over three sorted lists: drop the keys at the times of `out`, add those of `in`
  auto o = out.begin();
  auto i = in.begin();
  for (const Keyframe& k : *keys_) {
    while (o != out.end() && o->time < k.time) ++o;
    while (i != in.end() && i->time < k.time) keys->push_back(*i++);
    const bool dropped = o != out.end() && o->time == k.time;
    const bool replaced = i != in.end() && i->time == k.time;
    if (!dropped && !replaced) keys->push_back(k);
  }
  keys->insert(keys->end(), i, in.end());
  keys_ = std::move(keys);
}

std::size_t KeyChange::bytes() const {
  std::size_t n = 0;
  for (const auto* list : {&removed, &added}) {
    n += list->capacity() * sizeof(Keyframe);
    for (const Keyframe& k : *list) n += static_cast<std::size_t>(k.q.size()) * sizeof(double);
  }
  return n;
}

KeyChange diff_keys(const KeyTrack& before, const KeyTrack& after) {
  KeyChange c;
  if (before.shares_keys_with(after)) return c;
  const std::vector<Keyframe>& b = before.keys();
  const std::vector<Keyframe>& a = after.keys();
  std::size_t i = 0, j = 0;
  while (i < b.size() || j < a.size()) {
    if (j == a.size() || (i < b.size() && b[i].time < a[j].time)) {
      c.removed.push_back(b[i++]);
    } else if (i == b.size() || a[j].time < b[i].time) {
      c.added.push_back(a[j++]);
    } else {
      if (!(b[i] == a[j])) {
        c.removed.push_back(b[i]);
        c.added.push_back(a[j]);
      }
      ++i;
      ++j;
    }
  }
  return c;
}

KeyChange compose(const KeyChange& first, const KeyChange& second) {
  // per time: the key there before `first` and the key there after `second` (none: absent)
  struct Ends {
    bool by_first = false, by_second = false;
    std::optional<Keyframe> removed1, added1, removed2, added2;
  };
  std::map<double, Ends> times;
  auto note = [&times](const std::vector<Keyframe>& keys, bool Ends::*by,
                       std::optional<Keyframe> Ends::*slot) {
    for (const Keyframe& k : keys) {
      Ends& e = times[k.time];
      e.*by = true;
      e.*slot = k;
    }
  };
  note(first.removed, &Ends::by_first, &Ends::removed1);
  note(first.added, &Ends::by_first, &Ends::added1);
  note(second.removed, &Ends::by_second, &Ends::removed2);
  note(second.added, &Ends::by_second, &Ends::added2);
  KeyChange c;
  for (const auto& [t, e] : times) {
    const std::optional<Keyframe>& start = e.by_first ? e.removed1 : e.removed2;
    const std::optional<Keyframe>& end = e.by_second ? e.added2 : e.added1;
    if (start.has_value() == end.has_value() && (!start || *start == *end)) continue;
    if (start) c.removed.push_back(*start);
    if (end) c.added.push_back(*end);
  }
  return c;
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
  const Keys& keys = *keys_;
  if (keys.empty()) {
    q_out = core::neutral_configuration(model);
    return;
  }
  if (t <= keys.front().time) {
    q_out = keys.front().q;
    return;
  }
  if (t >= keys.back().time) {
    q_out = keys.back().q;
    return;
  }
  const auto it = std::upper_bound(keys.begin(), keys.end(), t,
                                   [](double tt, const Keyframe& k) { return tt < k.time; });
  const int i2 = static_cast<int>(it - keys.begin());
  const int i1 = i2 - 1;
  const Keyframe& k1 = keys[i1];
  const Keyframe& k2 = keys[i2];
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
  const Keyframe& k0 = keys[std::max(0, i1 - 1)];
  const Keyframe& k3 = keys[std::min(static_cast<int>(keys.size()) - 1, i2 + 1)];
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
