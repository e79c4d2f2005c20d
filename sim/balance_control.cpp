#include "sim/balance_control.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/com.hpp"
#include "sim/balance.hpp"
#include "sim/support_polygon.hpp"
#include "sim/world.hpp"

namespace sim {

namespace {

using core::Vector3;

constexpr double kMinNormalForce = 1.0;  // N: a link pressing less is not a support
// the share of the ground's push the supports (with the links below them, a toe) must carry for
// the figure to be standing on them
constexpr double kStandingShare = 0.9;

Vector3 on_plane(const Vector3& p, const GroundPlane& g, const Vector3& n) {
  return p - n * n.dot(p - g.point);
}

// The ground pair of body b on `link`, or nullptr.
const ContactPair* ground_pair(const World& world, int body, int link) {
  for (const ContactPair& p : world.contact_pairs()) {
    if (p.body == body && p.link == link && p.partner_body == -1 &&
        world.contact_points()[p.first_point].key.env == 0) {
      return &p;
    }
  }
  return nullptr;
}

// K = Σ (k_P / n_C) u uᵀ, u = r × n over a pair's points: how the ground's moment on the link
// about the pair's reference falls as the link tilts (from eq. 6.14); regularized so that an
// axis with no stiffness (about the normal) asks no tilt
Eigen::LDLT<core::Matrix3> tilt_stiffness(const World& world,
                                          const ContactPair& pair,
                                          const Vector3& n) {
  const double k_point = world.settings().contact.kp / pair.point_count;
  core::Matrix3 K = core::Matrix3::Zero();
  for (int k = 0; k < pair.point_count; ++k) {
    const Vector3 u = (world.contact_points()[pair.first_point + k].p_W - pair.ref_W).cross(n);
    K.noalias() += k_point * u * u.transpose();
  }
  K += (1e-6 * K.trace() + 1e-9) * core::Matrix3::Identity();
  return K.ldlt();
}

}  // namespace

// the ground's normal push on the supports and the links below them (a toe under its foot)
double BalanceFeedback::supported_load(const World& world,
                                       int body,
                                       const core::Model& model,
                                       const Vector3& n) const {
  double load = 0;
  for (const ContactPair& p : world.contact_pairs()) {
    if (p.body != body || p.partner_body != -1) continue;
    for (int link = p.link; link > 0; link = model.parent[link]) {
      const bool support = std::any_of(supports_.begin(), supports_.end(), [&](const Support& s) {
        return world.contact_pairs()[s.pair].link == link;
      });
      if (support) {
        load += n.dot(p.wrench.tail<3>());
        break;
      }
    }
  }
  return load;
}

const Vector3& BalanceFeedback::remember_footprint(int link, const Vector3& centre) {
  for (Footprint& f : footprints_) {
    if (f.link == link) {
      f.centre = centre;
      f.seen = true;
      return f.centre;
    }
  }
  footprints_.push_back({link, centre, true});
  return footprints_.back().centre;
}

Vector3 BalanceFeedback::footprint_of(int link, const Vector3& fallback) const {
  for (const Footprint& f : footprints_) {
    if (f.link == link) return f.centre;
  }
  return fallback;
}

// the mean of the footprints of this step's supporting pins; forgets the links no longer pinned
Vector3 BalanceFeedback::reference(const Vector3& fallback) {
  std::erase_if(footprints_, [](const Footprint& f) { return !f.seen; });
  Vector3 sum = Vector3::Zero();
  for (Footprint& f : footprints_) {
    sum += f.centre;
    f.seen = false;
  }
  return footprints_.empty() ? fallback : Vector3(sum / static_cast<double>(footprints_.size()));
}

// Moves the centre of pressure by Δ = p_d − p (p over all the body's ground contacts, F their
// total normal force): first by shifting load between the supports, the least change of their
// forces F_i with Σ F_i unchanged and Σ F_i a_i changed by F Δ (a_i their footprints; negative
// forces cut), then by moving each support's own CoP c_i by the same δ for what the shift leaves
// over, within its contact points.
void BalanceFeedback::distribute_load(const Vector3& cop, double total, const GroundPlane& ground) {
  const int count = static_cast<int>(supports_.size());
  const Vector3 n = ground.normal.normalized();
  const Vector3 u = n.unitOrthogonal(), w = n.cross(u);
  const Vector3 delta = state_.desired_cop - cop;
  Eigen::Matrix3Xd A(3, count);
  Eigen::VectorXd F(count);
  double supported = 0;
  for (int i = 0; i < count; ++i) {
    A.col(i) << 1.0, u.dot(supports_[i].footprint), w.dot(supports_[i].footprint);
    F[i] = supports_[i].force;
    supported += F[i];
  }
  const Eigen::Vector3d moment_now = A * F;
  const Eigen::Vector3d wanted =
      moment_now + total * Eigen::Vector3d(0, u.dot(delta), w.dot(delta));
  const Eigen::Matrix3d AAt = A * A.transpose() + 1e-9 * Eigen::Matrix3d::Identity();
  Eigen::VectorXd F_d = F + A.transpose() * AAt.ldlt().solve(wanted - moment_now);
  F_d = F_d.cwiseMax(0.0);
  if (F_d.sum() > 0) F_d *= supported / F_d.sum();
  const Eigen::Vector3d moved = (A * F_d - moment_now) / total;
  const Vector3 rest = (delta - moved.y() * u - moved.z() * w) * (total / supported);
  for (int i = 0; i < count; ++i) {
    Support& sp = supports_[i];
    sp.wanted_force = F_d[i];
    sp.wanted_cop = sp.polygon.size() >= 3
                        ? clamp_toward(sp.polygon, sp.cop + rest, sp.footprint, ground, 0.0)
                        : sp.cop;
  }
}

std::string validate(const BalanceSettings& s) {
  for (const auto& [name, value] : {std::pair{"frequency", s.frequency},
                                    {"margin", s.margin},
                                    {"max_tilt", s.max_tilt},
                                    {"support_frequency", s.support_frequency}}) {
    if (!std::isfinite(value) || value < 0) {
      return std::string("balance.") + name + ": must be a finite number >= 0";
    }
  }
  return {};
}

const BalanceState& BalanceFeedback::update(const World& world,
                                            int body,
                                            const core::Model& model,
                                            core::Data& data,
                                            const Eigen::VectorXd& v,
                                            const BalanceSettings& settings,
                                            const ik::Problem& problem,
                                            ik::Problem& solved) {
  solved = problem;
  state_ = BalanceState{};
  if (!settings.enabled) return state_;
  const GroundPlane& ground = world.environment().ground;
  const Vector3 n = ground.normal.normalized();
  const GroundReaction reaction = ground_reaction(world, body);
  const std::optional<Vector3> cop = center_of_pressure(world, body);
  if (!cop) return state_;
  polygon_ = support_polygon_of(world, body);
  if (polygon_.size() < 3) return state_;

  // the capture point and the CoP that sends it back over the support
  const Vector3 c = core::center_of_mass(model, data);
  const Vector3 c_dot = core::com_jacobian(model, data) * v;
  const double height = n.dot(c - ground.point);
  const double g = model.gravity.norm();
  if (!(height > 1e-3) || !(g > 0)) return state_;
  const double omega0 = std::sqrt(g / height);
  const Vector3 xi = on_plane(c + c_dot / omega0, ground, n);
  supports_.clear();
  // the supporting pins: orientation pins on links the ground presses on; pins on links that
  // have lifted keep their footprint while they are pinned
  for (ik::Problem::Entry& e : solved.entries()) {
    const auto* pin = std::get_if<ik::LinkTask>(&e.task);
    if (!pin || pin->role != ik::kPin || pin->mode == ik::TaskMode::kPosition) continue;
    for (Footprint& f : footprints_) f.seen = f.seen || f.link == pin->link;
    const ContactPair* pair = ground_pair(world, body, pin->link);
    if (!pair || !(n.dot(pair->wrench.tail<3>()) > kMinNormalForce)) continue;
    points_.clear();
    for (int k = 0; k < pair->point_count; ++k) {
      points_.push_back(world.contact_points()[pair->first_point + k].p_W);
    }
    std::vector<Vector3> own = support_polygon(points_, ground);
    Support sp;
    sp.entry = static_cast<int>(&e - solved.entries().data());
    sp.pair = static_cast<int>(pair - world.contact_pairs().data());
    // a link flat on the ground updates its footprint; one on an edge keeps the last
    sp.flat = own.size() >= 3;
    sp.footprint = sp.flat ? remember_footprint(pin->link, polygon_centroid(own, ground))
                           : footprint_of(pin->link, polygon_centroid(own, ground));
    sp.polygon = std::move(own);
    sp.force = n.dot(pair->wrench.tail<3>());
    sp.cop = pair->ref_W + n.cross(pair->wrench.head<3>()) / sp.force;
    supports_.push_back(std::move(sp));
  }
  const Vector3 polygon_centre = polygon_centroid(polygon_, ground);
  const Vector3 centre = reference(polygon_centre);
  const Vector3 wanted = xi + (settings.frequency / omega0) * (xi - centre);
  state_.capture_point = xi;
  state_.cop = *cop;
  state_.desired_cop =
      clamp_toward(polygon_, on_plane(wanted, ground, n), polygon_centre, ground, settings.margin);

  // a figure that rests on other links too (a knee, a hand, its back) is not standing on its
  // supports: there is no balance to keep
  const double total = n.dot(reaction.force);
  if (supports_.empty() || supported_load(world, body, model, n) < kStandingShare * total) {
    supports_.clear();
    return state_;
  }
  distribute_load(*cop, total, ground);
  for (const Support& sp : supports_) {
    ik::LinkTask& pin = std::get<ik::LinkTask>(solved.entries()[sp.entry].task);
    const ContactPair& pair = world.contact_pairs()[sp.pair];
    // the moment about the pair's reference that puts force F_d at the wanted CoP c_d
    const Vector3 dM =
        (sp.wanted_cop - pair.ref_W).cross(sp.wanted_force * n) - pair.wrench.head<3>();
    // the tilt from the pin's own orientation R₀ that gives that moment: the present one plus
    // −K⁻¹ ΔM; a link on an edge or a corner is turned back flat (R₀) first
    const core::Transform& X = data.X_W[pin.link];
    const core::Matrix3 R0 = pin.target_R_W.toRotationMatrix();
    Vector3 tilt = Vector3::Zero();
    if (sp.flat) {
      const Eigen::AngleAxisd now(X.R * R0.transpose());
      tilt = now.angle() * now.axis() - tilt_stiffness(world, pair, n).solve(dM);
      tilt -= n * n.dot(tilt);
      const double angle = tilt.norm();
      if (angle > settings.max_tilt) tilt *= settings.max_tilt / angle;
    }
    const double angle = tilt.norm();
    pin.target_R_W = core::Quaternion(
        angle > 0 ? core::Matrix3(Eigen::AngleAxisd(angle, tilt / angle) * R0) : R0);
    // the normal force is k_P times the mean penetration: press in by ΔF / k_P
    const double press = (sp.wanted_force - sp.force) / world.settings().contact.kp;
    pin.target_W = X.R * pin.p_LinkPoint + X.p - std::clamp(press, -1e-3, 1e-3) * n;
    pin.velocity_W.setZero();
    pin.mode = ik::TaskMode::kPose;
    pin.gain = settings.support_frequency;
  }
  state_.supports = static_cast<int>(supports_.size());
  state_.active = state_.supports > 0;
  return state_;
}

}  // namespace sim
