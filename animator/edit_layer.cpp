#include "animator/edit_layer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/configuration.hpp"

namespace animator {

double falloff_ease(double seconds, double falloff) {
  if (falloff <= 0 || seconds >= falloff) return 0.0;
  return 0.5 * (1.0 + std::cos(std::numbers::pi * seconds / falloff));
}

double EditLayer::blend(int frame, double frame_time) const {
  if (muted || displacement.empty()) return 0.0;
  if (frame >= first_frame && frame <= last_frame()) return weight;
  const int gap = frame < first_frame ? first_frame - frame : frame - last_frame();
  return weight * falloff_ease(gap * frame_time, falloff);
}

bool EditLayer::operator==(const EditLayer& o) const {
  return name == o.name && first_frame == o.first_frame && displacement == o.displacement &&
         falloff == o.falloff && weight == o.weight && muted == o.muted;
}

void layered_frame(const core::Model& model,
                   const core::Clip& base,
                   const LayerStack& layers,
                   int f,
                   Eigen::VectorXd& q_out) {
  q_out = base.frames[std::clamp(f, 0, base.size() - 1)];
  for (const auto& layer : layers) {
    const double w = layer->blend(f, base.frame_time);
    if (w == 0.0) continue;  // outside the window: untouched, bit for bit
    const int k = std::clamp(f, layer->first_frame, layer->last_frame()) - layer->first_frame;
    core::integrate(model, q_out, layer->displacement[k], w, q_out);
  }
}

void sample_layered(const core::Model& model,
                    const core::Clip& base,
                    const LayerStack& layers,
                    double t,
                    Eigen::VectorXd& q_out) {
  if (base.empty()) {
    q_out = core::neutral_configuration(model);
    return;
  }
  const double f = std::clamp(t / base.frame_time, 0.0, static_cast<double>(base.size() - 1));
  const int k = static_cast<int>(std::floor(f));
  const double s = f - k;
  if (s == 0.0 || k + 1 >= base.size()) {
    layered_frame(model, base, layers, k, q_out);
    return;
  }
  Eigen::VectorXd a, b;
  layered_frame(model, base, layers, k, a);
  layered_frame(model, base, layers, k + 1, b);
  core::interpolate(model, a, b, s, q_out);
}

core::Clip bake(const core::Model& model, const core::Clip& base, const LayerStack& layers) {
  core::Clip out;
  out.frame_time = base.frame_time;
  out.frames.resize(base.frames.size());
  for (int f = 0; f < base.size(); ++f) layered_frame(model, base, layers, f, out.frames[f]);
  return out;
}

}  // namespace animator
