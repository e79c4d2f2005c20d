// The contact and dynamics stages of sim::World: point forces, the implicit contact solve in
// contact space (sim/contact_dynamics.hpp) and forward dynamics with the contact wrenches.
#include <algorithm>

#include "core/aba.hpp"
#include "core/crba.hpp"
#include "core/jacobian.hpp"
#include "core/rnea.hpp"
#include "sim/world.hpp"

namespace sim {

namespace {

using core::Vector3;

// the 3 × 6 map from a pair's motion [ω; v] at its reference point to a point r away from it:
// ṗ = v + ω × r = [−[r ×], E] [ω; v] (Yamane eq. 6.24 in world axes)
Eigen::Matrix<double, 3, 6> point_map(const Vector3& r) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>() = -core::skew(r);
  J.rightCols<3>().setIdentity();
  return J;
}

// the velocity [ω; v] of a world point carried by `link` (world axes)
Vector6 link_point_motion(const core::Model& model,
                          const core::Data& data,
                          int link,
                          const Vector3& p_W) {
  const core::PointMotion m =
      core::point_velocity(model, data, link, data.X_W[link].inverse_apply(p_W));
  Vector6 out;
  out << m.angular, m.linear;
  return out;
}

}  // namespace

core::Vector3 World::anchor_of(const ContactPoint& p) const {
  for (const Anchor& a : anchors_) {
    if (!(a.key == p.key)) continue;
    if (p.key.partner_body < 0) return a.p_Partner;
    return work_[p.key.partner_body].data.X_W[p.key.partner_link] * a.p_Partner;
  }
  return p.p_W;  // a new contact anchors where it touched
}

void World::run_contact_forces() {
  counters_.count(Stage::kContactForces);
  const double h = settings_.step;
  point_forces_.resize(points_.size());
  point_states_.resize(points_.size());
  trials_.resize(points_.size());
  for (ContactPair& pair : pairs_) {
    const Work& wb = work_[pair.body];
    const Work* wa = pair.partner_body >= 0 ? &work_[pair.partner_body] : nullptr;
    auto relative_motion = [&](const Vector3& p_W) {
      Vector6 m = link_point_motion(*wb.dynamics, wb.data, pair.link, p_W);
      if (wa) m -= link_point_motion(*wa->dynamics, wa->data, pair.partner_link, p_W);
      return m;
    };
    pair.velocity = relative_motion(pair.ref_W);
    // the points' states and trial forces, then the pair's friction state (sim/soft_contact.hpp)
    const int first = pair.first_point, end = first + pair.point_count;
    double pair_normal = 0;
    for (int k = first; k < end; ++k) {
      const ContactPoint& p = points_[k];
      PointState& s = point_states_[k];
      s.position_W = p.p_W;
      s.normal_W = p.n_W;
      s.velocity_W = relative_motion(p.p_W).tail<3>();
      s.depth = p.depth;
      s.anchor_W = anchor_of(p);
      s.points_in_pair = pair.point_count;
      trials_[k] = trial_forces(s, settings_.contact);
      pair_normal += trials_[k].normal;
    }
    const FrictionState friction =
        scene_.friction ? pair_friction(&trials_[first], pair.point_count, settings_.contact)
                        : FrictionState::kOff;
    pair.sticking = friction == FrictionState::kStick;
    pair.wrench0.setZero();
    pair.K.setZero();
    pair.D.setZero();
    for (int k = first; k < end; ++k) {
      point_states_[k].pair_normal_force = pair_normal;
      const PointForce& f = point_forces_[k] =
          point_force(point_states_[k], settings_.contact, friction, h);
      // τ = Σ J_kᵀ f_k, K = Σ J_kᵀ F_p J_k, D = Σ J_kᵀ F_v J_k (Yamane eqs. 6.21, 6.29–6.30)
      const ContactPoint& p = points_[k];
      const Eigen::Matrix<double, 3, 6> J = point_map(p.p_W - pair.ref_W);
      pair.wrench0.noalias() += J.transpose() * f.force_W;
      pair.K.noalias() += J.transpose() * f.dF_dp * J;
      pair.D.noalias() += J.transpose() * f.dF_dv * J;
      // the anchor kept for the next step, in the partner's frame
      const Vector3 anchor =
          wa ? wa->data.X_W[p.key.partner_link].inverse_apply(f.anchor_W) : f.anchor_W;
      next_anchors_.push_back({p.key, anchor});
    }
  }
}

void World::compute_mass_matrix(int b) {
  Work& w = work_[b];
  if (w.mass_matrix_ready) return;
  const Body& body = bodies_[b];
  counters_.count(Stage::kBiasForces);
  w.bias = core::bias_forces(*w.dynamics, w.data, body.q, body.v);
  counters_.count(Stage::kMassMatrix);
  core::crba(*w.dynamics, w.data, body.q);
  core::factorize_mass_matrix(*w.dynamics, w.data);
  w.mass_matrix_ready = true;
}

void World::run_implicit_contact() {
  // pairs that touch a body moved by its dynamics-backed pins keep their explicit wrench (Yamane
  // ch. 9 uses the contact forces of the step's start); the others are solved implicitly
  implicit_index_.clear();
  for (int i = 0; i < static_cast<int>(pairs_.size()); ++i) {
    ContactPair& p = pairs_[i];
    const bool pinned =
        dynamically_pinned(p.body) || (p.partner_body >= 0 && dynamically_pinned(p.partner_body));
    if (pinned) {
      p.wrench = p.wrench0;
    } else {
      implicit_index_.push_back(i);
    }
  }
  if (implicit_index_.empty()) return;
  // the handles of every implicit pair, on the bodies they touch: the link (+), a partner (−)
  for (Work& w : work_) {
    w.handles.clear();
    w.handle_pair.clear();
    w.handle_sign.clear();
    w.handle_jdot_v.clear();
  }
  const int np = static_cast<int>(implicit_index_.size());
  for (int slot = 0; slot < np; ++slot) {
    const ContactPair& p = pairs_[implicit_index_[slot]];
    auto add = [&](int body, int link, double sign) {
      Work& w = work_[body];
      const Vector3 p_Link = w.data.X_W[link].inverse_apply(p.ref_W);
      w.handles.push_back({link, p_Link, true});
      w.handle_pair.push_back(slot);
      w.handle_sign.push_back(sign);
      const core::PointMotion jdv = core::point_jdot_v(*w.dynamics, w.data, link, p_Link);
      Vector6 a;
      a << jdv.angular, jdv.linear;
      w.handle_jdot_v.push_back(a);
    };
    add(p.body, p.link, 1.0);
    if (p.partner_body >= 0) add(p.partner_body, p.partner_link, -1.0);
  }
  Phi_.setZero(6 * np, 6 * np);
  free_acceleration_.setZero(6 * np);
  counters_.count(Stage::kOperationalSpace);
  for (int b = 0; b < body_count(); ++b) {
    Work& w = work_[b];
    if (w.handles.empty()) continue;
    compute_mass_matrix(b);
    core::compute_joint_jacobians(*w.dynamics, w.data);
    core::inverse_operational_inertia(*w.dynamics, w.data, w.handles, w.osim, w.Phi);
    // accelerations of the handles without contact: J H⁻¹ (τ − b) + J̇v
    w.scratch = joint_forces_of(b) - w.bias;
    core::solve_mass_matrix(*w.dynamics, w.data, w.scratch);
    const int nh = static_cast<int>(w.handles.size());
    for (int h = 0; h < nh; ++h) {
      const int slot = w.handle_pair[h];
      const double sh = w.handle_sign[h];
      free_acceleration_.segment<6>(6 * slot) +=
          sh * (w.osim.J.middleRows<6>(6 * h) * w.scratch + w.handle_jdot_v[h]);
      for (int g = 0; g < nh; ++g) {
        Phi_.block<6, 6>(6 * slot, 6 * w.handle_pair[g]) +=
            (sh * w.handle_sign[g]) * w.Phi.block<6, 6>(6 * h, 6 * g);
      }
    }
  }
  implicit_pairs_.resize(np);
  for (int slot = 0; slot < np; ++slot) implicit_pairs_[slot] = pairs_[implicit_index_[slot]];
  solve_implicit_wrenches(implicit_pairs_, Phi_, free_acceleration_, settings_.step, implicit_);
  for (int slot = 0; slot < np; ++slot) {
    pairs_[implicit_index_[slot]].wrench = implicit_pairs_[slot].wrench;
  }
}

void World::run_forward_dynamics() {
  counters_.count(Stage::kForwardDynamics);
  const double h = settings_.step;
  for (int b = 0; b < body_count(); ++b) {
    Work& w = work_[b];
    const Body& body = bodies_[b];
    if (w.pinned) continue;  // its accelerations came from its pins (run_dynamic_pins)
    if (w.falling) {
      // a fallen figure (sim/fall_response.hpp): H with its tone on the diagonal, factorized by
      // prepare_fallen; every pair's wrench on it, whether solved implicitly or not
      contact_joint_forces(b);
      w.generalized = w.fall.drive() - w.bias + w.contact_force;
      core::solve_mass_matrix(*w.dynamics, w.data, w.generalized);
      w.acceleration = w.generalized;
      w.fall.finish(w.acceleration);
    } else if (w.mass_matrix_ready && !w.handles.empty()) {
      // a = H⁻¹ (τ − b + Σ ±Jᵀ τ̂), with H factorized for the contact solve
      w.generalized = body.tau - w.bias;
      for (int k = 0; k < static_cast<int>(w.handles.size()); ++k) {
        w.generalized.noalias() += w.handle_sign[k] * w.osim.J.middleRows<6>(6 * k).transpose() *
                                   implicit_pairs_[w.handle_pair[k]].wrench;
      }
      core::solve_mass_matrix(*w.dynamics, w.data, w.generalized);
      w.acceleration = w.generalized;
    } else {
      bool loaded = false;
      for (const ContactPair& p : pairs_) {
        if (p.body != b && p.partner_body != b) continue;
        if (!loaded) std::fill(w.f_ext.begin(), w.f_ext.end(), core::Force::Zero());
        loaded = true;
        const Vector3 f = p.wrench.tail<3>(), n = p.wrench.head<3>();
        if (p.body == b)
          w.f_ext[p.link] += core::link_force_from_world(w.data, p.link, f, p.ref_W, n);
        if (p.partner_body == b) {
          w.f_ext[p.partner_link] -=
              core::link_force_from_world(w.data, p.partner_link, f, p.ref_W, n);
        }
      }
      if (loaded) {
        w.acceleration = core::aba(*w.dynamics, w.data, body.q, body.v, body.tau, w.f_ext);
      } else {
        w.acceleration = core::aba(*w.dynamics, w.data, body.q, body.v, body.tau);
      }
    }
    v_next_[b] = body.v + h * w.acceleration;
  }
}

}  // namespace sim
