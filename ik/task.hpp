// IK tasks: value objects, each a block of rows J θ̇ = ṗ_desired with a gain and a weight
// (Yamane §8.2, digest §2.2–2.3). Desired velocities are the feedback laws of digest §2.3.
#pragma once

#include <limits>
#include <variant>

#include "core/data.hpp"
#include "core/jacobian.hpp"
#include "core/model.hpp"

namespace ik {

using core::Quaternion;
using core::Vector3;

/// Which rows a link task constrains.
enum class TaskMode { kPosition, kOrientation, kPose };
const char* to_string(TaskMode m);

/// "use the solver's default" for a gain
constexpr double kDefaultGain = -1.0;

/// What a link task is for: a drag (the pointer; level 1 by default, Yamane eq. 8.8), a pin
/// (hold a point; level 3 by default, eqs. 8.21 and 8.30) or a reference (a preferred placement
/// of a link, as a joint reference is a preferred angle: level 3, the reference gain). The role
/// picks the default priority, the default gain and the name in the report; the rows are the
/// same.
enum class LinkRole { kDrag, kPin, kReference };
constexpr LinkRole kDrag = LinkRole::kDrag;
constexpr LinkRole kPin = LinkRole::kPin;
constexpr LinkRole kReference = LinkRole::kReference;
const char* to_string(LinkRole r);  // "drag", "pin", "reference"

/// Move a point on a link to a world target: position, orientation or both. Feedback law
/// ṙ = ṙ_ref + K (r_ref − r) (eq. 8.8), ω = ω_ref + K log(R_ref Rᵀ). A drag follows the pointer;
/// several are allowed (markers as drags, Yamane ch. 10). A pin holds its point, static (eq. 8.21)
/// or moving with feed-forward velocity (eq. 8.30, editing in motion); any link, any number.
struct LinkTask {
  LinkRole role = kDrag;
  int link = 0;
  Vector3 p_LinkPoint = Vector3::Zero();  // the grabbed or pinned point, link frame
  Vector3 target_W = Vector3::Zero();
  Quaternion target_R_W = Quaternion::Identity();  // orientation target (link frame in world)
  Vector3 velocity_W = Vector3::Zero();            // feed-forward ṙ_ref
  Vector3 angular_velocity_W = Vector3::Zero();    // feed-forward ω_ref
  TaskMode mode = TaskMode::kPosition;
  double gain = kDefaultGain;
  double weight = 1.0;  // row weight on the level it sits on (level 1 ignores it: it is exact)
};

/// Pull a joint toward a reference: 1-DOF θ̇ = θ̇_ref + K (θ_ref − θ) (eqs. 8.22, 8.31);
/// spherical ω = ω_ref + K log(Rᵀ R_ref) in the child frame (eqs. 8.24–8.26 with the rotation
/// vector in place of the skew part, so a 180° error still pulls).
struct JointReferenceTask {
  int joint = 0;
  double q_ref = 0;                                // 1-DOF joints
  Quaternion R_ref = Quaternion::Identity();       // spherical joints
  double velocity_ref = 0;                         // 1-DOF feed-forward
  Vector3 angular_velocity_ref = Vector3::Zero();  // spherical feed-forward, child frame
  double gain = kDefaultGain;
  double weight = 0.1;  // references are preferences: weaker than pins (1) by default
};

/// Number of rows a task contributes.
int task_rows(const core::Model& model, const LinkTask& t);
int task_rows(const core::Model& model, const JointReferenceTask& t);

/// Task error: position (m) and orientation (rad) parts, whichever the mode has.
struct TaskError {
  double position = 0;
  double orientation = 0;
};

/// Largest error the feedback term acts on in one step (the error is clamped to it).
struct ErrorClamp {
  double position = 0.2;     // m
  double orientation = 1.0;  // rad
};

/// Fills the rows of J (task Jacobian, world-aligned; orientation rows before position rows)
/// and v (desired velocity) for the current kinematics, with the feedback gain K.
/// Requires: core::compute_joint_jacobians(model, data, q).
void fill_link_task(const core::Model& model,
                    const core::Data& data,
                    const LinkTask& t,
                    double K,
                    const ErrorClamp& clamp,
                    Eigen::Ref<Eigen::MatrixXd> J,
                    Eigen::Ref<Eigen::VectorXd> v);

/// Fills the selection rows of a joint reference (one per coordinate of the joint: 1 at the
/// coordinate, 0 elsewhere) and their desired velocities.
void fill_reference_task(const core::Model& model,
                         const Eigen::VectorXd& q,
                         const JointReferenceTask& t,
                         double K,
                         const ErrorClamp& clamp,
                         Eigen::Ref<Eigen::MatrixXd> J,
                         Eigen::Ref<Eigen::VectorXd> v);
/// The desired velocities of a joint reference alone, for callers that keep selection rows
/// as coordinate indices instead of dense rows.
void reference_task_velocity(const core::Model& model,
                             const Eigen::VectorXd& q,
                             const JointReferenceTask& t,
                             double K,
                             const ErrorClamp& clamp,
                             Eigen::Ref<Eigen::VectorXd> v);

/// Current error of a link task. Requires: core::forward_kinematics.
TaskError link_task_error(const core::Data& data, const LinkTask& t);
TaskError reference_task_error(const core::Model& model,
                               const Eigen::VectorXd& q,
                               const JointReferenceTask& t);

/// The mode named by to_string ("position", "orientation", "pose"); nullopt for other text.
std::optional<TaskMode> task_mode_from_string(std::string_view s);

}  // namespace ik
