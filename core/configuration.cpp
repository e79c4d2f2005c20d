#include "core/configuration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace core {

Eigen::VectorXd neutral_configuration(const Model& model) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq);
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    if (model.joint_type[i] == JointType::kSpherical) q[iq] = 1.0;
    if (model.joint_type[i] == JointType::kFree) q[iq + 3] = 1.0;
  }
  return q;
}

Eigen::VectorXd rest_configuration(const Model& model) {
  constexpr double kOffEnd = 0.02;  // fraction of the way to the middle of the range
  Eigen::VectorXd q = neutral_configuration(model);
  for (int i = 1; i < model.njoints; ++i) {
    const JointType t = model.joint_type[i];
    if (t != JointType::kRevolute && t != JointType::kPrismatic) continue;
    const JointLimits& L = model.limits[i];
    double value = 0;
    if (std::isfinite(L.lower) && std::isfinite(L.upper))
      value = kOffEnd * 0.5 * (L.lower + L.upper);
    q[model.idx_q[i]] = std::clamp(value, L.lower, L.upper);
  }
  return q;
}

State neutral_state(const Model& model) {
  return {neutral_configuration(model), Eigen::VectorXd::Zero(model.nv)};
}

void integrate(const Model& model,
               const Eigen::VectorXd& q,
               const Eigen::VectorXd& v,
               double dt,
               Eigen::VectorXd& q_out) {
  if (&q_out != &q) q_out = q;
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    const int iv = model.idx_v[i];
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        q_out[iq] = q[iq] + v[iv] * dt;
        break;
      case JointType::kSpherical: {
        // body-frame angular velocity: R ← R exp(ω dt)
        const Quaternion r = quaternion_at(q, iq) * quaternion_exp(v.segment<3>(iv) * dt);
        set_quaternion_at(q_out, iq, r.normalized());
        break;
      }
      case JointType::kFree: {
        // body twist: X ← X exp6(V dt)
        const Transform X{quaternion_at(q, iq + 3).normalized().toRotationMatrix(),
                          q.segment<3>(iq)};
        const Motion V{v.segment<3>(iv) * dt, v.segment<3>(iv + 3) * dt};
        const Transform Xn = X * exp6(V);
        q_out.segment<3>(iq) = Xn.p;
        const Quaternion r = quaternion_at(q, iq + 3) * quaternion_exp(V.angular);
        set_quaternion_at(q_out, iq + 3, r.normalized());
        break;
      }
    }
  }
}

Eigen::VectorXd integrate(const Model& model,
                          const Eigen::VectorXd& q,
                          const Eigen::VectorXd& v,
                          double dt) {
  Eigen::VectorXd out(model.nq);
  integrate(model, q, v, dt, out);
  return out;
}

void difference(const Model& model,
                const Eigen::VectorXd& q0,
                const Eigen::VectorXd& q1,
                Eigen::VectorXd& v_out) {
  v_out.resize(model.nv);
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    const int iv = model.idx_v[i];
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute:
      case JointType::kPrismatic:
        v_out[iv] = q1[iq] - q0[iq];
        break;
      case JointType::kSpherical: {
        const Quaternion r0 = quaternion_at(q0, iq).normalized();
        const Quaternion r1 = quaternion_at(q1, iq).normalized();
        v_out.segment<3>(iv) = quaternion_log(r0.conjugate() * r1);
        break;
      }
      case JointType::kFree: {
        const Quaternion r0 = quaternion_at(q0, iq + 3).normalized();
        const Quaternion r1 = quaternion_at(q1, iq + 3).normalized();
        const Transform X0{r0.toRotationMatrix(), q0.segment<3>(iq)};
        const Transform X1{r1.toRotationMatrix(), q1.segment<3>(iq)};
        const Motion V = log6(X0.inverse() * X1);
        v_out.segment<3>(iv) = V.angular;
        v_out.segment<3>(iv + 3) = V.linear;
        break;
      }
    }
  }
}

Eigen::VectorXd difference(const Model& model,
                           const Eigen::VectorXd& q0,
                           const Eigen::VectorXd& q1) {
  Eigen::VectorXd v(model.nv);
  difference(model, q0, q1, v);
  return v;
}

namespace {
// splitmix64: a tiny generator whose output is identical on every platform
struct SplitMix64 {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // uniform rotation (Shoemake, "Uniform random rotations", Graphics Gems III)
  Quaternion rotation() {
    const double u1 = uniform(), u2 = uniform(), u3 = uniform();
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    const double t2 = 2 * std::numbers::pi * u2, t3 = 2 * std::numbers::pi * u3;
    Quaternion r(b * std::cos(t3), a * std::sin(t2), a * std::cos(t2), b * std::sin(t3));
    if (r.w() < 0) r.coeffs() *= -1;
    return r;
  }
};
}  // namespace

Eigen::VectorXd random_configuration(const Model& model, std::uint64_t seed) {
  SplitMix64 rng{seed};
  Eigen::VectorXd q = neutral_configuration(model);
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    const JointLimits& L = model.limits[i];
    switch (model.joint_type[i]) {
      case JointType::kFixed:
        break;
      case JointType::kRevolute: {
        const bool bounded = std::isfinite(L.lower) && std::isfinite(L.upper);
        q[iq] = bounded ? rng.uniform(L.lower, L.upper)
                        : rng.uniform(-std::numbers::pi, std::numbers::pi);
        break;
      }
      case JointType::kPrismatic: {
        const bool bounded = std::isfinite(L.lower) && std::isfinite(L.upper);
        q[iq] = bounded ? rng.uniform(L.lower, L.upper) : rng.uniform(-1.0, 1.0);
        break;
      }
      case JointType::kSpherical:
        set_quaternion_at(q, iq, rng.rotation());
        break;
      case JointType::kFree:
        for (int k = 0; k < 3; ++k) q[iq + k] = rng.uniform(-1.0, 1.0);
        set_quaternion_at(q, iq + 3, rng.rotation());
        break;
    }
  }
  return q;
}

void normalize(const Model& model, Eigen::VectorXd& q) {
  for (int i = 1; i < model.njoints; ++i) {
    int iq = model.idx_q[i];
    if (model.joint_type[i] == JointType::kFree)
      iq += 3;
    else if (model.joint_type[i] != JointType::kSpherical)
      continue;
    set_quaternion_at(q, iq, quaternion_at(q, iq).normalized());
  }
}

std::string check_configuration(const Model& model, const Eigen::VectorXd& q, double tol) {
  if (q.size() != model.nq) {
    return "configuration has " + std::to_string(q.size()) + " entries, the model needs " +
           std::to_string(model.nq);
  }
  for (int i = 1; i < model.njoints; ++i) {
    const int iq = model.idx_q[i];
    const int nq = joint_nq(model.joint_type[i]);
    if (!q.segment(iq, nq).allFinite()) {
      return "joint '" + model.joint_name[i] + "': configuration is not finite";
    }
    int iquat = -1;
    if (model.joint_type[i] == JointType::kSpherical) iquat = iq;
    if (model.joint_type[i] == JointType::kFree) iquat = iq + 3;
    if (iquat >= 0 && std::abs(q.segment<4>(iquat).norm() - 1.0) > tol) {
      return "joint '" + model.joint_name[i] + "': quaternion is not unit length";
    }
  }
  return {};
}

}  // namespace core
