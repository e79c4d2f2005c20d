// Session (animator/session.hpp): keys, the base clip and its edit layers, the animation sampled
// frame by frame, and the budgets that bound them (animator/limits.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "animator/session.hpp"

namespace animator {

namespace {

std::string count_text(std::int64_t n) { return std::to_string(n); }

std::string seconds_text(double s) {
  std::ostringstream out;
  out.precision(12);
  out << s;
  return out.str();
}

// frames of the keys sampled at `rate` (the last key's time included), clamped far above any
// budget so that a huge key time cannot overflow
std::int64_t key_frames(double duration, double rate) {
  const double n = std::floor(duration * rate + 1e-9) + 1;
  return n < 1e15 ? static_cast<std::int64_t>(n) : std::int64_t{1'000'000'000'000'000};
}

}  // namespace

// --- budgets -------------------------------------------------------------------------------------

void Session::set_limits(const Limits& limits) {
  if (const std::string e = check_limits(limits); !e.empty()) throw SessionError("limits", e);
  limits_ = limits;
  history_.set_byte_budget(limits.max_undo_bytes);
}

void Session::check_key_time(double time) const {
  if (!std::isfinite(time) || time < 0) throw SessionError("time", "must be a finite time >= 0");
  if (time > limits_.max_clip_seconds) {
    throw BudgetError("time", seconds_text(time) + " s is beyond the limit of " +
                                  seconds_text(limits_.max_clip_seconds) + " s per clip (set by " +
                                  kMaxClipSecondsSetting + ")");
  }
}

void Session::check_clip_budget(std::int64_t frames,
                                double frame_time,
                                const std::string& field) const {
  const std::string why =
      io::clip_budget_refusal(clip_budget(limits_), frames, frame_time, model_->nq);
  if (why.empty()) return;
  if (field.empty()) throw BudgetError(why);
  throw BudgetError(field, why);
}

std::int64_t Session::recording_frame_budget() const {
  const double rate = kDefaultClipRate;
  const double by_seconds = std::floor(limits_.max_clip_seconds * rate + 1e-9) + 1;
  const std::int64_t by_values = limits_.max_clip_values / std::max(1, model_->nq);
  return std::min(
      {limits_.max_clip_frames, by_values, static_cast<std::int64_t>(std::min(by_seconds, 1e15))});
}

// --- keyframes -----------------------------------------------------------------------------------

int Session::key_insert(std::optional<double> time, Interpolation interpolation) {
  const double t = time.value_or(playback_.time);
  check_key_time(t);
  if (doc_.keys.find(t, 1e-9) < 0 && doc_.keys.size() >= limits_.max_keys) {
    throw BudgetError("the session has " + count_text(doc_.keys.size()) +
                      " keys, the most it may hold (set by " + kMaxKeysSetting +
                      "; delete keys or bake them into the clip to add more)");
  }
  const Document before = doc_;
  const int index = doc_.keys.insert(Keyframe{t, doc_.q, interpolation});
  commit(before, "insert key");
  return index;
}

void Session::key_delete(int index) {
  if (index < 0 || index >= doc_.keys.size()) {
    throw SessionError("index", "no key " + std::to_string(index));
  }
  const Document before = doc_;
  doc_.keys.remove(index);
  commit(before, "delete key");
}

int Session::key_move(int index, double time) {
  if (index < 0 || index >= doc_.keys.size()) {
    throw SessionError("index", "no key " + std::to_string(index));
  }
  check_key_time(time);
  const Document before = doc_;
  const int moved = doc_.keys.move(index, time);
  commit(before, "move key");
  return moved;
}

void Session::key_set_interpolation(int index, Interpolation interpolation) {
  if (index < 0 || index >= doc_.keys.size()) {
    throw SessionError("index", "no key " + std::to_string(index));
  }
  const Document before = doc_;
  Keyframe k = doc_.keys.keys()[index];
  k.interpolation = interpolation;
  doc_.keys.insert(std::move(k));
  commit(before, "key interpolation");
}

void Session::bake_keys(double rate) {
  if (doc_.keys.empty()) throw SessionError("there are no keys to bake");
  if (!std::isfinite(rate) || rate <= 0 || rate > 1000)
    throw SessionError("rate", "must be in (0, 1000]");
  const std::int64_t n = key_frames(doc_.keys.duration(), rate);
  check_clip_budget(n, 1.0 / rate, "rate");
  core::Clip clip;
  clip.frame_time = 1.0 / rate;
  clip.frames.resize(static_cast<std::size_t>(n));
  for (std::int64_t f = 0; f < n; ++f)
    doc_.keys.sample(*model_, static_cast<double>(f) / rate, clip.frames[f]);
  set_clip(std::move(clip), "bake keys");
}

// --- clips and layers ----------------------------------------------------------------------------

void Session::set_clip(core::Clip clip,
                       const std::string& label,
                       std::shared_ptr<const ClipMarkers> markers) {
  if (const std::string e = core::check_clip(*model_, clip); !e.empty())
    throw SessionError("clip", e);
  if (clip.empty()) throw SessionError("clip", "has no frames");
  check_clip_budget(clip.size(), clip.frame_time, "clip");
  if (markers) {
    std::string e = check_clip_markers(*model_, markers->set, markers->measured);
    if (e.empty()) e = check_markers_fit_clip(*markers, clip);
    if (!e.empty()) throw SessionError("markers", e);
  }
  const Document before = doc_;
  doc_.clip = std::make_shared<const core::Clip>(std::move(clip));
  doc_.markers = std::move(markers);
  doc_.layers.clear();
  playback_.time = std::clamp(playback_.time, 0.0, doc_.clip->duration());
  show_animation_at(playback_.time);
  commit(before, label);
}

namespace {
void check_layer(const LayerStack& layers, int index) {
  if (index < 0 || index >= static_cast<int>(layers.size())) {
    throw SessionError("index", "no layer " + std::to_string(index));
  }
}
}  // namespace

void Session::set_layer_muted(int index, bool muted) {
  check_layer(doc_.layers, index);
  const Document before = doc_;
  auto copy = std::make_shared<EditLayer>(*doc_.layers[index]);
  copy->muted = muted;
  doc_.layers[index] = copy;
  show_animation_at(playback_.time);
  commit(before, muted ? "mute layer" : "unmute layer");
}

void Session::set_layer_weight(int index, double weight) {
  check_layer(doc_.layers, index);
  if (!std::isfinite(weight) || weight < 0 || weight > 10)
    throw SessionError("weight", "must be in [0, 10]");
  const Document before = doc_;
  auto copy = std::make_shared<EditLayer>(*doc_.layers[index]);
  copy->weight = weight;
  doc_.layers[index] = copy;
  show_animation_at(playback_.time);
  commit(before, "layer weight");
}

void Session::remove_layer(int index) {
  check_layer(doc_.layers, index);
  const Document before = doc_;
  doc_.layers.erase(doc_.layers.begin() + index);
  show_animation_at(playback_.time);
  commit(before, "remove layer");
}

void Session::bake_layers() {
  if (!doc_.clip) throw SessionError("there is no clip to bake the layers into");
  const Document before = doc_;
  doc_.clip = std::make_shared<const core::Clip>(bake(*model_, *doc_.clip, doc_.layers));
  doc_.layers.clear();
  commit(before, "bake layers");
}

// --- the animation, frame by frame ---------------------------------------------------------------

std::int64_t Session::animation_frames() const {
  if (doc_.clip) return doc_.clip->size();
  if (doc_.keys.empty()) return 1;
  return key_frames(doc_.keys.duration(), kDefaultClipRate);
}

double Session::animation_frame_time() const {
  return doc_.clip ? doc_.clip->frame_time : 1.0 / kDefaultClipRate;
}

void Session::animation_frame(std::int64_t f, Eigen::VectorXd& q_out) const {
  const std::int64_t n = animation_frames();
  if (f < 0 || f >= n) {
    throw SessionError("frame", "must be below the animation's " + count_text(n) + " frames");
  }
  if (doc_.clip) {
    layered_frame(*model_, *doc_.clip, doc_.layers, static_cast<int>(f), q_out);
  } else if (!doc_.keys.empty()) {
    // the same expression animation_clip() samples with, so the frame is bit-identical
    doc_.keys.sample(*model_, static_cast<double>(f) / kDefaultClipRate, q_out);
  } else {
    q_out = doc_.q;
  }
}

core::Clip Session::animation_clip(std::int64_t first, std::int64_t last) const {
  const std::int64_t n = animation_frames();
  if (first < 0 || first >= n) {
    throw SessionError("first", "must be a frame of the animation's " + count_text(n));
  }
  if (last < first || last >= n) {
    throw SessionError("last", "must be in [first, " + count_text(n - 1) + "]");
  }
  core::Clip out;
  out.frame_time = animation_frame_time();
  try {
    check_clip_budget(last - first + 1, out.frame_time, "");
  } catch (const BudgetError& e) {
    throw BudgetError("frames " + count_text(first) + " to " + count_text(last) + " of the " +
                      "animation: " + e.what() + " (ask for fewer frames at a time)");
  }
  out.frames.resize(static_cast<std::size_t>(last - first + 1));
  for (std::int64_t f = first; f <= last; ++f) animation_frame(f, out.frames[f - first]);
  return out;
}

core::Clip Session::animation_clip() const { return animation_clip(0, animation_frames() - 1); }

double Session::duration() const {
  if (doc_.clip) return doc_.clip->duration();
  return doc_.keys.duration();
}

}  // namespace animator
