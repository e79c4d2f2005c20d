// A simulated world: articulated bodies (the character, props), the static environment, the
// scene's effects and a fixed-step clock. The step is a pipeline of stages (sim/stages.hpp) built
// from the effects: a stage no effect needs does not run, and every stage that runs is counted.
//
//   effect alone      stages that run in each step
//   (none)            nothing: the world holds still, as posing does
//   gravity           forward dynamics (ABA), integration
//   ground_contact,   kinematics, collision search; while anything touches: contact forces, and
//   self_collision    for the implicit integrator bias forces, mass matrix, operational space;
//                     forward dynamics, integration
//   friction          nothing by itself: it shapes the forces of the two above
//   hard_limits       forward dynamics, limit projection (with the mass matrix in a step where a
//                     joint reaches a limit), integration
//   dynamic_pins      (sim/dynamic_pins: the pins' stages)
//
// Thread contract: a World is a value; one thread at a time steps it. Copying it copies the
// whole state (the clock, every body's q and v, the friction anchors), so saving and restoring a
// world is a copy.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/data.hpp"
#include "core/model.hpp"
#include "core/osim.hpp"
#include "ik/acceleration_solver.hpp"
#include "ik/problem.hpp"
#include "sim/balance_control.hpp"
#include "sim/collision.hpp"
#include "sim/contact_dynamics.hpp"
#include "sim/environment.hpp"
#include "sim/fall_response.hpp"
#include "sim/scene.hpp"
#include "sim/settings.hpp"
#include "sim/shapes.hpp"
#include "sim/soft_contact.hpp"
#include "sim/stages.hpp"

namespace sim {

/// A request the world refuses; what() names the field and the rule.
class SimError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct Body {
  std::string name;
  std::shared_ptr<const core::Model> model;
  Eigen::VectorXd q;    // configuration (nq)
  Eigen::VectorXd v;    // velocity (nv)
  Eigen::VectorXd tau;  // joint forces applied during every step (nv), zero unless set
};

/// One velocity constraint of the hard_limits stage (sim/world_limits.cpp).
struct LimitRow {
  int coordinate = 0;  // velocity coordinate
  double allowed = 0;  // the velocity the row allows at most (upper), at least (lower), or asks
  int side = 0;        // +1: upper limit (impulse <= 0), −1: lower limit (>= 0), 0: a hold
  int q_index = -1;    // 1-DOF joints: the coordinate placed on `limit` after an impact
  double limit = 0;
};

class World {
 public:
  explicit World(const WorldSettings& settings = {}, const Environment& environment = {});

  // --- bodies ---------------------------------------------------------------------------
  /// Adds a body; v empty means at rest. @throws SimError naming the body and the field
  int add_body(const std::string& name,
               std::shared_ptr<const core::Model> model,
               const Eigen::VectorXd& q,
               const Eigen::VectorXd& v = {});
  int body_count() const { return static_cast<int>(bodies_.size()); }
  const Body& body(int i) const { return bodies_.at(i); }
  /// -1 when no body has this name.
  int body_index(const std::string& name) const;
  void set_state(int i, const Eigen::VectorXd& q, const Eigen::VectorXd& v);
  void set_joint_forces(int i, const Eigen::VectorXd& tau);

  // --- dynamics-backed pins (the dynamic_pins effect, sim/world_pins.cpp) -----------------
  /// The drag, pins and joint references of body i, solved at acceleration level while the
  /// scene has dynamic_pins (ik/acceleration_solver.hpp): the body's joints move as the tasks
  /// ask, its root as the contact forces and gravity make it. Needs a free root.
  /// @throws SimError when the body's root is not a free joint
  void set_pin_problem(int i, const ik::Problem& problem);
  void clear_pin_problem(int i);
  /// The problem of body i, to move its targets between steps; nullptr when it has none.
  ik::Problem* pin_problem(int i);
  void set_pin_settings(const ik::AccelerationSettings& settings);
  /// The balance feedback of dynamically pinned bodies (sim/balance_control.hpp); on by default.
  void set_balance_settings(const BalanceSettings& settings);
  const BalanceSettings& balance_settings() const { return balance_settings_; }
  /// The collision shapes of body i's links.
  const BodyShapes& shapes(int i) const { return work_.at(i).shapes; }
  /// What the balance feedback of body i did in its last step.
  const BalanceState& balance_state(int i) const { return work_.at(i).balance.state(); }
  /// The solver of body i after its last dynamic-pins step (torques, report); nullptr when none.
  const ik::AccelerationSolver* pin_solver(int i) const;
  /// What a dynamically pinned body does once it has fallen (sim/fall_response.hpp).
  void set_fall_settings(const FallSettings& settings);
  const FallSettings& fall_settings() const { return fall_settings_; }
  /// Body i has fallen (its centre of mass low, on the ground): its pins let go until its state
  /// is set again (set_state).
  bool fallen(int i) const { return work_.at(i).fall.fallen(); }
  /// The joint forces the dynamic-pins stage drove body i with in its last step: the pins'
  /// torques, or once fallen its muscle tone and the drag's spring (with the body's own tau);
  /// nullptr when the stage did not drive it.
  const Eigen::VectorXd* driving_forces(int i) const;

  // --- what is simulated ------------------------------------------------------------------
  void set_scene(const Scene& scene);
  const Scene& scene() const { return scene_; }
  /// @throws SimError naming the first bad field
  void set_settings(const WorldSettings& settings);
  const WorldSettings& settings() const { return settings_; }
  void set_environment(const Environment& environment);
  const Environment& environment() const { return environment_; }
  /// Something moves when stepped: an effect other than friction is on.
  bool simulates() const;

  // --- time -------------------------------------------------------------------------------
  /// Advances the world by `dt` seconds of wall time: as many fixed steps as that covers, the
  /// remainder carried to the next call, so simulated time tracks the summed dt to within one
  /// step whatever the call rate. Returns the number of steps taken. @throws SimError for a
  /// negative or non-finite dt
  int advance(double dt);
  /// Exactly one fixed step.
  void step();
  double time() const { return time_; }
  std::uint64_t steps() const { return steps_; }

  // --- what happened ----------------------------------------------------------------------
  const StageCounters& counters() const { return counters_; }
  void reset_counters() { counters_.reset(); }
  /// Contact points, pairs and point forces found at the start of the last step.
  const std::vector<ContactPoint>& contact_points() const { return points_; }
  const std::vector<ContactPair>& contact_pairs() const { return pairs_; }
  const std::vector<PointForce>& point_forces() const { return point_forces_; }
  /// Kinetic and potential energy of body i (J); potential energy only with gravity on.
  double kinetic_energy(int i) const;
  double potential_energy(int i) const;
  double energy() const;

 private:
  // per-body workspace: sized once, rebuilt when the scene changes gravity
  struct Work {
    std::shared_ptr<const core::Model> dynamics;  // the model, with gravity off unless the scene
    core::Data data;                              // has it
    BodyShapes shapes;
    std::vector<int> sweep_order;
    Eigen::VectorXd acceleration, bias, generalized, scratch;
    std::vector<core::Force> f_ext;
    // contact handles on this body: the pairs it takes part in
    std::vector<core::Handle> handles;
    std::vector<int> handle_pair;
    std::vector<double> handle_sign;  // +1: the pair's link, −1: its partner link
    std::vector<Vector6> handle_jdot_v;
    core::OsimWorkspace osim;
    Eigen::MatrixXd Phi;
    bool mass_matrix_ready = false;
    // dynamics-backed pins: the tasks, the solver (a fresh workspace in every copy) and the
    // contact forces as joint forces Q = Σ J_kᵀ f_k
    std::optional<ik::Problem> pins;
    std::shared_ptr<ik::AccelerationSolver> pin_solver;
    Eigen::VectorXd contact_force;
    core::FrameJacobian handle_jacobian;
    bool pinned = false;  // its accelerations came from the pins this step
    FallResponse fall;
    bool falling = false;  // fallen: driven by fall.drive() with fall.diagonal() in its LTDL
    BalanceFeedback balance;
    ik::Problem balanced_pins;  // the pins with the balance feedback's targets
    explicit Work(const core::Model& m) : data(m) {}
    Work(const Work& o);
    Work& operator=(const Work& o);
    Work(Work&&) = default;
    Work& operator=(Work&&) = default;
  };
  struct Anchor {
    FeatureKey key;
    core::Vector3 p_Partner;  // partner frame (world for the environment)
  };

  void rebuild_dynamics_models();
  void step_euler();
  void step_rk4();
  // stages
  void run_kinematics();
  void run_collision_search();
  void run_contact_forces();
  void run_implicit_contact();
  bool dynamically_pinned(int b) const;
  bool on_ground(int b) const;  // the ground pushes on body b this step
  bool has_pins(int b) const;   // dynamic pins on and body b has a problem
  bool let_go(int b) const;     // has_pins, but body b has fallen: passive, with its tone
  void prepare_fallen();
  const Eigen::VectorXd& joint_forces_of(int b) const;  // its drive when fallen, else its tau
  void run_dynamic_pins();
  void contact_joint_forces(int b);
  void run_forward_dynamics();
  void run_limit_projection();
  void run_integration();
  void keep_anchors();
  // helpers
  void compute_mass_matrix(int b);
  core::Vector3 anchor_of(const ContactPoint& p) const;
  void accelerations_at(const std::vector<Eigen::VectorXd>& q,
                        const std::vector<Eigen::VectorXd>& v,
                        std::vector<Eigen::VectorXd>& a);

  WorldSettings settings_;
  Environment environment_;
  Scene scene_;
  std::vector<Body> bodies_;
  std::vector<Work> work_;
  double time_ = 0;
  double remainder_ = 0;
  std::uint64_t steps_ = 0;
  StageCounters counters_;
  // contacts of the current step
  std::vector<ContactPoint> points_;
  std::vector<ContactPair> pairs_;
  std::vector<PointForce> point_forces_;
  std::vector<PointState> point_states_;
  std::vector<Trial> trials_;
  std::vector<Anchor> anchors_, next_anchors_;
  ImplicitWorkspace implicit_;
  std::vector<ContactPair> implicit_pairs_;  // the pairs solved implicitly (no pinned body)
  std::vector<int> implicit_index_;          // their indices in pairs_
  ik::AccelerationSettings pin_settings_;
  BalanceSettings balance_settings_;
  FallSettings fall_settings_;
  Eigen::MatrixXd Phi_;
  Eigen::VectorXd free_acceleration_;
  // hard limits: rows, H⁻¹ columns and impulses
  std::vector<LimitRow> limit_rows_;
  Eigen::MatrixXd limit_columns_;
  std::vector<double> limit_impulses_;
  struct LimitSnap {
    int body = 0, q_index = 0;
    double value = 0;
  };
  std::vector<LimitSnap> limit_snaps_;
  // per body velocities after the dynamics stage, before integration
  std::vector<Eigen::VectorXd> v_next_;
  // RK4 stages
  std::vector<Eigen::VectorXd> rk_q_, rk_v_, rk_kq_[4], rk_kv_[4], rk_q0_, rk_v0_;
};

}  // namespace sim
