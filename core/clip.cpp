#include "core/clip.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/configuration.hpp"

namespace core {

void interpolate(const Model& model,
                 const Eigen::VectorXd& q0,
                 const Eigen::VectorXd& q1,
                 double s,
                 Eigen::VectorXd& q_out) {
  if (s == 0.0) {
    q_out = q0;
    return;
  }
  if (s == 1.0) {
    q_out = q1;
    return;
  }
  q_out.resize(model.nq);
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        q_out[iq] = (1 - s) * q0[iq] + s * q1[iq];
        break;
      case JointType::kFree:
        q_out.segment<3>(iq) = (1 - s) * q0.segment<3>(iq) + s * q1.segment<3>(iq);
        set_quaternion_at(q_out, iq + 3,
                          quaternion_at(q0, iq + 3).slerp(s, quaternion_at(q1, iq + 3)));
        break;
      case JointType::kSpherical:
        set_quaternion_at(q_out, iq, quaternion_at(q0, iq).slerp(s, quaternion_at(q1, iq)));
        break;
    }
  }
}

void sample(const Model& model, const Clip& clip, double t, Eigen::VectorXd& q_out) {
  if (clip.empty()) {
    q_out = neutral_configuration(model);
    return;
  }
  const double f = std::clamp(t / clip.frame_time, 0.0, static_cast<double>(clip.size() - 1));
  const int k = std::min(static_cast<int>(std::floor(f)), clip.size() - 1);
  const double s = f - k;
  if (s == 0.0 || k + 1 >= clip.size()) {
    q_out = clip.frames[k];
    return;
  }
  interpolate(model, clip.frames[k], clip.frames[k + 1], s, q_out);
}

void sample_velocity(const Model& model, const Clip& clip, double t, Eigen::VectorXd& v_out) {
  v_out = Eigen::VectorXd::Zero(model.nv);
  if (clip.size() < 2) return;
  const double f = std::clamp(t / clip.frame_time, 0.0, static_cast<double>(clip.size() - 1));
  const int k = static_cast<int>(std::lround(f));
  const int a = std::max(0, k - 1), b = std::min(clip.size() - 1, k + 1);
  difference(model, clip.frames[a], clip.frames[b], v_out);
  v_out /= (b - a) * clip.frame_time;
}

std::string check_clip(const Model& model, const Clip& clip) {
  if (!std::isfinite(clip.frame_time) || clip.frame_time <= 0) {
    return "frame time must be a finite number > 0";
  }
  for (int k = 0; k < clip.size(); ++k) {
    const std::string e = check_configuration(model, clip.frames[k], 1e-6);
    if (!e.empty()) return "frame " + std::to_string(k) + ": " + e;
  }
  return {};
}

}  // namespace core
