#include "animator/motion_editor.hpp"

#include <algorithm>

#include "core/configuration.hpp"
#include "core/jacobian.hpp"
#include "core/kinematics.hpp"

namespace animator {

namespace {
// weight of the rows that pull every joint back onto the clip: far below the pins (1), so a pin
// stays within a millimetre when the drag makes them disagree
constexpr double kClipReferenceWeight = 1e-4;
}  // namespace

ik::SolverSettings motion_edit_settings(double frame_time) {
  ik::SolverSettings s;
  s.dt = frame_time;
  s.iterations = 3;
  // K h = 1 for each of the iterations: every iteration is a full Gauss–Newton step toward this
  // frame's targets, so the pins land on the clip's trajectory instead of lagging behind it (the
  // target's motion over the frame enters through the error; a separate feed-forward term would
  // count it twice)
  const double full = s.iterations / frame_time;
  s.pin_gain = full;
  s.reference_gain = full;
  s.drag_gain = full;
  s.max_joint_step = 0.5;
  // the targets move smoothly and stay reachable, so a light damping keeps pins within a
  // millimetre (the posing default trades that accuracy for calm behaviour at unreachable drags)
  s.damping = 1e-3;
  return s;
}

MotionEditor::MotionEditor(const core::Model& model, const ik::SolverSettings& settings)
    : model_(model),
      solver_(model, settings),
      data_(model),
      ref_data_(model),
      frame_time_(settings.dt) {}

void MotionEditor::begin(const core::Clip& base, const LayerStack& layers, int frame) {
  recorded_.clear();
  last_solved_ = -1;
  layered_frame(model_, base, layers, frame, q_);
}

const Eigen::VectorXd& MotionEditor::edit(const core::Clip& base,
                                          const LayerStack& layers,
                                          int frame,
                                          const std::vector<Pin>& pins,
                                          const std::optional<ik::LinkTask>& drag) {
  // the reference: this frame of the layered clip. The solve starts from the clip frame carrying
  // the previous frame's displacement, so joints the pins and the drag do not need keep moving
  // with the clip, and the damping resists changes of the edit rather than the clip's motion.
  layered_frame(model_, base, layers, frame, q_ref_);
  core::forward_kinematics(model_, ref_data_, q_ref_);
  if (last_solved_ < 0) {
    q_ = q_ref_;
  } else {
    core::integrate(model_, q_ref_, recorded_.at(last_solved_).displacement, 1.0, q_);
  }

  problem_.clear();
  // moving pins: the pinned points follow the clip (eq. 8.30 with the full-gain feedback above)
  for (const Pin& p : pins) {
    problem_.add(ik::LinkTask{.role = ik::kPin,
                              .link = p.link,
                              .p_LinkPoint = p.p_LinkPoint,
                              .target_W = ref_data_.X_W[p.link] * p.p_LinkPoint,
                              .target_R_W = core::Quaternion(ref_data_.X_W[p.link].R),
                              .mode = p.mode});
  }
  // every joint follows the clip weakly (8.31), so only what the drag and pins need changes
  for (int j = 1; j < model_.njoints; ++j) {
    const core::JointType t = model_.joint_type[j];
    if (t != core::JointType::kRevolute && t != core::JointType::kPrismatic &&
        t != core::JointType::kSpherical) {
      continue;
    }
    ik::JointReferenceTask r{.joint = j, .weight = kClipReferenceWeight};
    const int iq = model_.idx_q[j];
    if (t == core::JointType::kSpherical) {
      r.R_ref = core::quaternion_at(q_ref_, iq);
    } else {
      r.q_ref = q_ref_[iq];
    }
    problem_.add(r);
  }
  if (drag) problem_.add(*drag);
  problem_.enforce_ranges = false;  // captured motion is kept as captured outside the edit
  solver_.step(problem_, data_, q_);
  // the edited frame, as a displacement over the layered clip
  Eigen::VectorXd delta(model_.nv);
  core::difference(model_, q_ref_, q_, delta);
  recorded_[frame] = Recorded{std::move(delta), last_solved_};
  last_solved_ = frame;
  return q_;
}

std::shared_ptr<const EditLayer> MotionEditor::finish(const std::string& name, double falloff) {
  if (recorded_.empty()) return nullptr;
  auto layer = std::make_shared<EditLayer>();
  layer->name = name;
  layer->falloff = falloff;
  layer->first_frame = recorded_.begin()->first;
  layer->displacement.resize(recorded_.rbegin()->first - layer->first_frame + 1);
  for (auto it = recorded_.begin(); it != recorded_.end(); ++it) {
    const int a = it->first;
    const Eigen::VectorXd& da = it->second.displacement;
    layer->displacement[a - layer->first_frame] = da;
    const auto next = std::next(it);
    if (next == recorded_.end()) break;
    const int b = next->first;
    const Eigen::VectorXd& db = next->second.displacement;
    const bool stepped_over = next->second.previous == a;  // one pass went from a straight to b
    for (int f = a + 1; f < b; ++f) {
      double wa, wb;
      if (stepped_over) {
        wb = double(f - a) / double(b - a);
        wa = 1.0 - wb;
      } else {
        wa = falloff_ease((f - a) * frame_time_, falloff);
        wb = falloff_ease((b - f) * frame_time_, falloff);
        const double sum = wa + wb;
        if (sum > 1.0) wa /= sum, wb /= sum;
      }
      layer->displacement[f - layer->first_frame] = wa * da + wb * db;
    }
  }
  recorded_.clear();
  last_solved_ = -1;
  return layer;
}

}  // namespace animator
