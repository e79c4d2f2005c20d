// Editing in motion (Yamane §8.4, digest §2.6): the pin-and-drag solver run at every frame of a
// clip. Pins become moving pins that follow the clip's link trajectories (eq. 8.30), every joint
// follows the clip's angles as a weak moving reference (eq. 8.31), and a drag pulls on top. The
// result is kept as an edit layer over the untouched clip.
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <vector>

#include "animator/edit_layer.hpp"
#include "animator/pin.hpp"
#include "core/clip.hpp"
#include "core/data.hpp"
#include "ik/solver.hpp"

namespace animator {

/// The settings editing in motion starts from: several iterations per frame so moving pins stay
/// within a millimetre, and references that pull the joints back onto the clip.
ik::SolverSettings motion_edit_settings(double frame_time);

class MotionEditor {
 public:
  MotionEditor(const core::Model& model, const ik::SolverSettings& settings);

  /// Starts an edit at frame f of the layered clip: the edited pose starts on the clip.
  void begin(const core::Clip& base, const LayerStack& layers, int frame);

  /// Solves frame f: pins follow the layered clip (their link points' trajectories), joints
  /// follow its angles weakly, and the drag (if any) pulls on top. Records the frame's
  /// displacement. Returns the edited pose. The solve starts from the frame solved before it, so
  /// an edit whose clock wrapped to the loop's start goes on as the same edit (one gesture, one
  /// layer); a frame solved again replaces its record.
  const Eigen::VectorXd& edit(const core::Clip& base,
                              const LayerStack& layers,
                              int frame,
                              const std::vector<Pin>& pins,
                              const std::optional<ik::LinkTask>& drag);

  /// The recorded frames as an edit layer, or null when nothing was recorded. Frames the edit
  /// stepped over are interpolated linearly between the frames before and after; frames between
  /// two passes of a wrapped edit that neither reached ease out from both sides over `falloff`
  /// seconds (the cosine of EditLayer::blend), so the gesture's frames are exact and the frames
  /// it never touched are not carried along.
  std::shared_ptr<const EditLayer> finish(const std::string& name, double falloff);

  const Eigen::VectorXd& pose() const { return q_; }
  const ik::Report& report() const { return solver_.report(); }

 private:
  const core::Model& model_;
  ik::Solver solver_;
  core::Data data_, ref_data_;
  Eigen::VectorXd q_, q_ref_;
  struct Recorded {
    Eigen::VectorXd displacement;
    int previous = -1;  // the frame solved just before this one in the gesture, -1 for the first
  };
  std::map<int, Recorded> recorded_;  // frame → its displacement
  int last_solved_ = -1;              // the frame solved last (warm start of the next)
  double frame_time_;
  ik::Problem problem_;
};

}  // namespace animator
