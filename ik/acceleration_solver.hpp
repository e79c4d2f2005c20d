// The pin-and-drag solver at acceleration level: the dynamics-backed pin of Yamane ch. 9, in the
// standard floating-base form of digest §2.8 (reference/digest-check.md, appendix A).
//
// For a figure whose root is a free joint, θ = (θ_b, q), the first six rows of the equation of
// motion H θ̈ + b = (0; τ) + Q (Q = Σ J_kᵀ f_k, the contact forces as joint forces) fix the root:
//     θ̈_b = H_bb⁻¹ (Q_b − b_b − H_bq q̈),
// so every handle's acceleration r̈ = J θ̈ + J̇ θ̇ is a function of the joint accelerations alone:
//     r̈_i = Γ_i q̈ + J_ib H_bb⁻¹ (Q_b − b_b) + J̇_i θ̇,     Γ_i = J_iq − J_ib H_bb⁻¹ H_bq
// (J_ib H_bb⁻¹ Q_b is the book's Φ^lock f, J̇θ̇ − J_ib H_bb⁻¹ b_b its ψ). Each task row asks
//     Γ_i q̈ = r̈ᵈ_i − J_ib H_bb⁻¹ (Q_b − b_b) − J̇_i θ̇                        (Yamane eq. 9.23)
// and the rows are solved level by level as at velocity level (ik/solver.hpp): 1. the drag,
// exactly (damped only along directions that lose rank); 2. joint ranges; 3. pins and joint
// references, with the SR inverse — each in the null space of the levels above. Nothing pushes
// the dragged link: it moves because the joints move it, so the rest of the body reacts.
//
// Desired accelerations are the acceleration form of the feedback laws (digest §2.3):
//     r̈ᵈ = K_v (ṙ_ref − ṙ) + K_p (r_ref − r) = K_v (ṙᵈ − ṙ),
// with ṙᵈ the velocity-level law of ik/task.hpp at gain K_p / K_v, critically damped:
// K_p = ω², K_v = 2ω for a natural frequency ω (rad/s) per task kind (a task's own `gain`, when
// set, is its ω). Joint references and range rows use the same law on joint velocities.
//
// The torques follow from inverse dynamics with the contact forces as external forces:
//     τ = H_qb θ̈_b + H_qq q̈ + b_q − Q_q,
// so forward dynamics with τ and the same contact forces reproduces θ̈ (tests/ik).
//
// Allocation-free once the workspace has seen a problem of this size (level 1 holds at most
// kMaxDragRows rows).
#pragma once

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <string>

#include "core/data.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"
#include "ik/limits.hpp"
#include "ik/problem.hpp"
#include "ik/sr_inverse.hpp"

namespace ik {

/// Most rows level 1 (the drags) may hold at acceleration level: two 6-D drags.
constexpr int kMaxDragRows = 12;

struct AccelerationSettings {
  double drag_frequency = 10.0;        // ω of the drag (rad/s): K_p = ω², K_v = 2ω
  double pin_frequency = 10.0;         // ω of the pins
  double reference_frequency = 3.0;    // ω of the joint references
  double range_frequency = 20.0;       // ω of the rows that pull a joint back into its range
  double top_singular_value = 0.1;     // level 1: singular values below this are damped
  double top_damping = 1e-2;           // level 1: the damping those directions get
  double range_damping = 1e-3;         // level 2: SR k
  double damping = 1e-2;               // level 3: SR k of the pins and references
  double max_position_error = 0.1;     // m, the error clamp of the feedback laws
  double max_orientation_error = 1.0;  // rad
  double step = 1e-3;                  // s: the control step, for range predictions
  // bounds on the joints (not the root): accelerations beyond max_joint_acceleration are scaled
  // down together, then each joint's is cut so that its speed after the step stays within
  // max_joint_speed; a drag the body cannot follow (a falling figure held by the hand) then
  // lags instead of winding the joints up
  double max_joint_acceleration = 300.0;  // rad/s² (m/s² for prismatic joints)
  double max_joint_speed = 25.0;          // rad/s
  bool use_joint_weights = true;          // scale joints by the model's ik_weight
};

/// Empty when usable, else a message naming the first bad field.
std::string validate(const AccelerationSettings& s);

struct AccelerationReport {
  enum class Status { kOk, kRejected };
  Status status = Status::kOk;
  std::string message;  // why the problem was rejected
  int top_rows = 0, range_rows = 0, lower_rows = 0;
  int top_rank = 0;
  bool top_damped = false;
  double root_residual = 0;  // |H_bb θ̈_b + H_bq q̈ + b_b − Q_b|: the root rows of the EOM
  bool bounded = false;      // the joint accelerations were cut by the bounds of the settings
};

class AccelerationSolver {
 public:
  explicit AccelerationSolver(const core::Model& model, const AccelerationSettings& s = {});

  /// Solves the accelerations and torques of one step.
  /// Requires: the root is a free joint (joint 1); core::forward_kinematics(q, v) and
  /// core::compute_joint_jacobians with the same q; data.M from core::crba(q); `bias` = b(q, v)
  /// (gravity included); `contact` = Q = Σ J_kᵀ f_k (nv), the contact forces as joint forces.
  const AccelerationReport& solve(const Problem& problem,
                                  const core::Data& data,
                                  const Eigen::VectorXd& q,
                                  const Eigen::VectorXd& v,
                                  const Eigen::VectorXd& bias,
                                  const Eigen::VectorXd& contact);

  /// θ̈ (nv): the root's six, then the joints'.
  const Eigen::VectorXd& acceleration() const { return acceleration_; }
  /// τ (nv): zero in the root's six rows.
  const Eigen::VectorXd& torque() const { return torque_; }
  const AccelerationReport& report() const { return report_; }
  const AccelerationSettings& settings() const { return settings_; }
  void set_settings(const AccelerationSettings& s) { settings_ = s; }

 private:
  std::string check(const Problem& problem, const Eigen::VectorXd& q) const;
  void split_root(const core::Data& data, const Eigen::VectorXd& bias, const Eigen::VectorXd& Q);
  void fill_rows(const Problem& problem,
                 const core::Data& data,
                 const Eigen::VectorXd& q,
                 const Eigen::VectorXd& v);
  void reserve_rows(Eigen::MatrixXd& A, Eigen::VectorXd& b, int rows);
  void add_selection_rows(bool top,
                          int coordinate,
                          int rows,
                          const Eigen::Ref<const Eigen::VectorXd>& velocity_desired,
                          double frequency,
                          double weight,
                          const Eigen::VectorXd& v);
  void add_row_block(bool top,
                     const Eigen::Ref<const Eigen::MatrixXd>& J,
                     const Eigen::Ref<const Eigen::VectorXd>& velocity_desired,
                     const Eigen::Ref<const Eigen::VectorXd>& jdot_v,
                     double frequency,
                     double weight,
                     const Eigen::VectorXd& v);
  void project(const Eigen::Ref<const Eigen::MatrixXd>& A,
               Eigen::Ref<Eigen::MatrixXd> out,
               bool with_level2);
  void solve_levels();
  bool bound_joint_accelerations(const Eigen::VectorXd& v);
  void hold_at_ranges(const Eigen::VectorXd& v);
  void finish(const core::Data& data, const Eigen::VectorXd& bias, const Eigen::VectorXd& Q);

  const core::Model& model_;
  AccelerationSettings settings_;
  AccelerationReport report_;
  int n_ = 0;  // joint coordinates (nv − 6)

  // the root split: X = H_bb⁻¹ H_bq (6 × n), y = H_bb⁻¹ (Q_b − b_b) (6)
  Eigen::Matrix<double, 6, 6> Hbb_;
  Eigen::MatrixXd X_;
  Eigen::Matrix<double, 6, 1> y_;
  // task rows in weight-scaled joint coordinates: A x = b with q̈ = diag(col_scale) x
  Eigen::MatrixXd A1_, A2_, A3_;  // level 1 (drag), 2 (ranges), 3 (pins, references)
  Eigen::VectorXd b1_, b2_, b3_;
  int m1_ = 0, m2_ = 0, m3_ = 0;
  Eigen::VectorXd col_scale_;
  // row filling scratch
  Eigen::MatrixXd J_;  // one task's rows over all nv coordinates (≤ 6 × nv)
  Eigen::VectorXd vd_, jdv_;
  std::vector<RangeRow> range_rows_;
  std::vector<char> range_flags_;
  int range_violations_ = 0;  // range_rows_ begins with the joints already beyond their ranges
  // levels
  using SmallMatrix =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDragRows, kMaxDragRows>;
  using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDragRows, 1>;
  SmallMatrix G1_, G1inv_;
  Eigen::SelfAdjointEigenSolver<SmallMatrix> eigen1_;
  SmallVector t1_;
  // the null space of levels 1 and 2, N = E − A1ᵀ P1 − S2ᵀ P2, kept in that factored form
  Eigen::MatrixXd P1_;            // level 1: G1⁺ A1 (kMaxDragRows × n)
  Eigen::MatrixXd S2_, G2_, P2_;  // level 2: S2 = A2 N, its Gram matrix, G2⁻¹ S2
  Eigen::MatrixXd C_;             // scratch: rows · A1ᵀ or rows · S2ᵀ
  Eigen::MatrixXd S3_;            // level 3: S3 = A3 N
  Eigen::VectorXd x_, r_, y3_, t2_;
  SrInverse sr_;
  // results
  Eigen::VectorXd acceleration_, torque_;
};

}  // namespace ik
