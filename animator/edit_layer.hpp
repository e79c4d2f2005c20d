// Edit layers: a motion edit kept as a displacement over the untouched clip below it
// (editing in motion, Yamane §8.4). Frames outside the layer's window and falloff are returned
// bit-identical to the clip below.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/clip.hpp"
#include "core/model.hpp"

namespace animator {

struct EditLayer {
  std::string name;
  int first_frame = 0;  // the edited frames are [first_frame, first_frame + displacement.size())
  std::vector<Eigen::VectorXd> displacement;  // per edited frame: edited = below ⊕ δ (nv each)
  double falloff = 0.5;  // seconds over which the edit fades in before and out after its frames
  double weight = 1.0;   // scales the displacement
  bool muted = false;

  int last_frame() const { return first_frame + static_cast<int>(displacement.size()) - 1; }
  /// Blend factor at a frame: weight inside the edited frames, a smooth (cosine) ramp over the
  /// falloff, and exactly 0 beyond it.
  double blend(int frame, double frame_time) const;
  bool operator==(const EditLayer& o) const;
};

using LayerStack = std::vector<std::shared_ptr<const EditLayer>>;

/// The fade of an edit `seconds` away from its edited frames: a cosine ease from 1 (at them) to
/// 0 at `falloff` and beyond, with zero slope at both ends; 0 for a falloff of 0.
double falloff_ease(double seconds, double falloff);

/// Frame f of the clip with the unmuted layers applied in order.
void layered_frame(const core::Model& model,
                   const core::Clip& base,
                   const LayerStack& layers,
                   int f,
                   Eigen::VectorXd& q_out);

/// The layered motion at time t (interpolated between layered frames).
void sample_layered(const core::Model& model,
                    const core::Clip& base,
                    const LayerStack& layers,
                    double t,
                    Eigen::VectorXd& q_out);

/// The clip with every unmuted layer applied (what "bake" keeps).
core::Clip bake(const core::Model& model, const core::Clip& base, const LayerStack& layers);

}  // namespace animator
