// What a figure driven by the dynamics-backed pins does once it has fallen. Standing, the pins'
// torques are whatever the tasks ask (Yamane ch. 9 bounds none of them). On its feet that is what
// posing wants; on the ground it is not: joints of unbounded strength, still chasing the drag and
// the standing posture, push off the floor and heave the whole figure up (two metres in a test
// drag), which no person's muscles could do. So a figure whose centre of mass has dropped below a
// fraction of its standing height while the ground pushes on it has fallen, and lets go until its
// state is set again (the book, of a figure that fails to keep balance: "it never recovers"):
//   - its pins and joint references stop acting as constraints; it is a passive body again, its
//     contacts solved implicitly like any other's;
//   - each joint keeps some muscle tone, a spring-damper toward its reference posture,
//       τ_j = K_j e_j − D_j q̇_j,  K_j = tone · g Σ_{k beyond j} m_k |c_k − o_j|,
//       D_j = 2 ζ √(K_j H_jj),
//     with e_j the joint's error to its reference (the rotation vector log(Rᵀ R_ref) of a
//     spherical joint, in the child frame). K_j is `tone` times the torque gravity makes at full
//     reach of the links beyond j, per radian, so a limb sags and the body cannot lift itself; a
//     spring toward a fixed posture and a damper add no energy. The tone acts at the step's end
//     (backward Euler), so it is stable whatever the posture;
//   - the drag becomes a spring on the grabbed point, as a hand pulling a rag doll:
//       F = k (target − p) − c ṗ,  k = F_max / reach,  c = 2 √(k m_beyond),
//     its spring part at most F_max, a fraction of the figure's weight, applied as Jᵀ F: the
//     user's pull is the only energy that comes in.
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/data.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"
#include "ik/problem.hpp"
#include "sim/environment.hpp"

namespace sim {

struct FallSettings {
  bool enabled = true;
  /// Fallen once the centre of mass is below this fraction of its standing height over the
  /// ground (the figure's neutral posture standing; a deep squat keeps about 0.55).
  double com_height = 0.4;
  double tone = 0.3;           // joint stiffness: this fraction of the gravity torque at full reach
  double damping_ratio = 1.0;  // ζ of each joint's spring-damper
  double drag_force = 0.25;    // the drag's largest pull, in weights of the figure
  double drag_reach = 0.1;     // m: the distance at which the drag pulls with its largest force
  bool operator==(const FallSettings&) const = default;
};

/// Empty when usable, else a message naming the first bad field.
std::string validate(const FallSettings& s);

class FallResponse {
 public:
  FallResponse() = default;
  /// The figure's standing height and each joint's reach torque, from its neutral posture.
  FallResponse(const core::Model& model, const GroundPlane& ground);

  /// Latches `fallen` once the centre of mass is low while the ground pushes on the body (in the
  /// air it is falling, not fallen). Requires: the step's kinematics in `data`.
  bool update(const core::Model& model,
              core::Data& data,
              const GroundPlane& ground,
              bool on_ground,
              const FallSettings& settings);
  bool fallen() const { return fallen_; }
  /// Stands the response down (a new state was set).
  void reset() { fallen_ = false; }

  /// The fallen figure's drive for a step of h seconds: its own joint forces `tau`, its muscle
  /// tone toward the problem's joint references and the drag's spring. The tone is taken at the
  /// step's end (backward Euler on the spring-damper, stable whatever the gains and the posture):
  ///     (H + diag(h D + h² K)) a = drive − b + Q,   drive = τ + K e − (D + h K) v + Jᵀ F,
  /// so the world adds diagonal() to the mass matrix it factorizes for this body and uses drive()
  /// as its joint forces (contacts stay implicit). Requires: the step's kinematics with
  /// velocities, joint Jacobians and mass matrix (core::crba) in `data`.
  void prepare(const core::Model& model,
               const core::Data& data,
               const Eigen::VectorXd& q,
               const Eigen::VectorXd& v,
               const Eigen::VectorXd& tau,
               const ik::Problem& problem,
               const FallSettings& settings,
               double h);
  const Eigen::VectorXd& drive() const { return drive_; }
  const Eigen::VectorXd& diagonal() const { return diagonal_; }
  /// Records the joint forces that drove the step, drive − diagonal ∘ a, for its accelerations a.
  void finish(const Eigen::VectorXd& a);
  const Eigen::VectorXd& joint_forces() const { return applied_; }

  /// Centre of mass height over the ground standing (m).
  double standing_height() const { return standing_height_; }

 private:
  void add_tone(const core::Model& model,
                const core::Data& data,
                const Eigen::VectorXd& q,
                const Eigen::VectorXd& v,
                const ik::JointReferenceTask& reference,
                const FallSettings& settings,
                double h);
  void add_drag_spring(const core::Model& model,
                       const core::Data& data,
                       const Eigen::VectorXd& v,
                       const ik::LinkTask& drag,
                       const FallSettings& settings);

  double standing_height_ = 0;
  double weight_ = 0;                // N
  Eigen::VectorXd reach_torque_;     // per velocity coordinate: g Σ m_k |c_k − o_j| (N m)
  std::vector<double> mass_beyond_;  // per link: the mass of its subtree (kg)
  bool fallen_ = false;
  Eigen::VectorXd drive_, diagonal_, applied_;
  core::FrameJacobian jacobian_;
};

}  // namespace sim
