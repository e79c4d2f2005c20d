#include "animator/session.hpp"

#include <algorithm>
#include <cmath>

#include "core/configuration.hpp"
#include "core/kinematics.hpp"

namespace animator {

namespace {

// an id shared by the consecutive commands of one gesture, so they merge into one undo entry
constexpr int kMovePinGesture = 1 << 30;

bool finite(const core::Vector3& v) { return v.allFinite(); }

}  // namespace

Session::Session(std::shared_ptr<const core::Model> model, std::string character)
    : model_(std::move(model)), character_(std::move(character)), data_(*model_) {
  doc_.q = core::rest_configuration(*model_);  // limbs slightly off straight: see its comment
  doc_.settings.hard_pins = true;  // a pin holds while the user drags (docs/ik.md, "Pin strength")
  doc_.settings.floor = true;      // posing stays on the floor (animator/floor_contacts.hpp)
  floor_ = std::make_unique<FloorContacts>(*model_);
  solver_ = std::make_unique<ik::Solver>(*model_, doc_.settings);
  pin_hold_ = std::make_unique<ik::PinHold>(*model_);
  refresh_kinematics();
}

void Session::check_link(int link) const {
  if (link < 1 || link >= model_->njoints) {
    throw SessionError("link", "link index " + std::to_string(link) +
                                   " is out of range (the character has links 1.." +
                                   std::to_string(model_->njoints - 1) + ")");
  }
}

void Session::refresh_kinematics() { core::forward_kinematics(*model_, data_, doc_.q); }

void Session::commit(const Document& before, const std::string& label) {
  // each edit gets its own gesture id, so the settling that follows can be folded into it
  last_gesture_ = ++gesture_counter_;
  history_.record(std::make_unique<DocumentChange>(before, doc_, label, last_gesture_));
}

void Session::apply_document(const Document& doc) {
  doc_ = doc;
  solver_->set_settings(doc_.settings);
  settling_ = false;
  refresh_kinematics();
  sync_physics(/*restart=*/true);
}

void Session::restore(Document doc, const Playback& playback) {
  if (const std::string e = core::check_configuration(*model_, doc.q); !e.empty()) {
    throw SessionError("q", e);
  }
  drag_.reset();
  motion_editor_.reset();
  recording_.reset();
  apply_document(doc);
  playback_ = playback;
  history_.clear();
}

Session::Checkpoint Session::checkpoint() const {
  return Checkpoint{history_.checkpoint(), gesture_counter_, last_gesture_, edit_counter_};
}

void Session::roll_back(const Document& doc, const Playback& playback, Checkpoint checkpoint) {
  if (const std::string e = core::check_configuration(*model_, doc.q); !e.empty()) {
    throw SessionError("q", e);
  }
  drag_.reset();
  gesture_before_.reset();
  motion_editor_.reset();
  motion_edit_frame_ = -1;
  recording_.reset();
  apply_document(doc);
  playback_ = playback;
  playback_.playing = false;
  history_.restore(std::move(checkpoint.history));
  gesture_counter_ = checkpoint.gesture_counter;
  last_gesture_ = checkpoint.last_gesture;
  edit_counter_ = checkpoint.edit_counter;
}

// --- pose ------------------------------------------------------------------------------------

void Session::set_pose(const Eigen::VectorXd& q) {
  if (const std::string e = core::check_configuration(*model_, q, 1e-6); !e.empty()) {
    throw SessionError("q", e);
  }
  const Document before = doc_;
  doc_.q = q;
  refresh_kinematics();
  sync_physics(/*restart=*/true);
  commit(before, "set pose");
}

// --- dragging ----------------------------------------------------------------------------------

void Session::drag_begin(int link,
                         const core::Vector3& target_W,
                         const core::Vector3& p_LinkPoint) {
  check_link(link);
  if (!finite(target_W)) throw SessionError("target_W", "must be 3 finite numbers");
  if (!finite(p_LinkPoint)) throw SessionError("p_LinkPoint", "must be 3 finite numbers");
  const bool over_clip = doc_.clip && doc_.clip->size() > 1 && !physics_;
  const bool in_motion = over_clip && playback_.playing;
  if (over_clip && static_cast<int>(doc_.layers.size()) >= limits_.max_layers) {
    throw BudgetError("the session has " + std::to_string(doc_.layers.size()) +
                      " edit layers, the most it may hold (set by " + kMaxLayersSetting +
                      "; bake or remove layers to edit the clip again)");
  }
  if (drag_) drag_end();  // a lost drag_end: close the previous gesture first
  gesture_before_ = doc_;
  drag_ = Drag{};
  drag_->link = link;
  drag_->p_LinkPoint = p_LinkPoint;
  drag_->target_W = target_W;
  drag_->previous_target_W = target_W;
  drag_->root_R_W = data_.X_W[1].R;
  floor_gesture_ = false;  // the floor's contacts are taken afresh for this gesture
  if (in_motion) {
    start_motion_edit();
  } else if (over_clip) {
    // a paused clip: the drag edits the frame shown (the nearest frame, shown exactly), and
    // pins are moving pins that hold where their links are at that frame, not where they were
    // when pinned at another frame
    const int frame = clip_frame_at(playback_.time);
    drag_->edit_frame = frame;
    playback_.time = frame * doc_.clip->frame_time;
    layered_frame(*model_, *doc_.clip, doc_.layers, frame, doc_.q);
    refresh_kinematics();
    for (Pin& p : doc_.pins) {
      p.target_W = data_.X_W[p.link] * p.p_LinkPoint;
      p.target_R_W = core::Quaternion(data_.X_W[p.link].R);
    }
  }
  settling_ = true;
}

void Session::drag_move(const core::Vector3& target_W,
                        const std::optional<core::Quaternion>& rotation) {
  if (!drag_) throw SessionError("no drag in progress (drag_begin first)");
  if (!finite(target_W)) throw SessionError("target_W", "must be 3 finite numbers");
  if (rotation && (!rotation->coeffs().allFinite() || std::abs(rotation->norm() - 1) > 1e-3)) {
    throw SessionError("rotation", "must be a unit quaternion [w, x, y, z]");
  }
  drag_->target_W = target_W;
  if (rotation) drag_->rotation = rotation->normalized();
}

void Session::drag_end() {
  if (!drag_) return;
  if (motion_editor_) finish_motion_edit();
  const int edit_frame = drag_->edit_frame;
  drag_.reset();
  if (edit_frame >= 0 && doc_.clip) keep_frame_edit(edit_frame);
  if (gesture_before_) {
    commit(*gesture_before_, "drag");
    gesture_before_.reset();
  }
  // pins pulled away by the drag recover through their feedback; a kept frame edit shows the
  // layered clip, which has nothing to recover
  settling_ = edit_frame < 0;
}

std::optional<int> Session::dragged_link() const {
  if (!drag_) return std::nullopt;
  return drag_->link;
}

// --- pins ----------------------------------------------------------------------------------------

void Session::pin(int link, ik::TaskMode mode, const core::Vector3& p_LinkPoint) {
  check_link(link);
  if (!finite(p_LinkPoint)) throw SessionError("p_LinkPoint", "must be 3 finite numbers");
  const Document before = doc_;
  std::erase_if(doc_.pins, [&](const Pin& p) { return p.link == link; });
  doc_.pins.push_back(Pin{link, mode, p_LinkPoint, data_.X_W[link] * p_LinkPoint,
                          core::Quaternion(data_.X_W[link].R)});
  commit(before, "pin " + model_->link_name[link]);
}

void Session::unpin(int link) {
  check_link(link);
  const Document before = doc_;
  if (std::erase_if(doc_.pins, [&](const Pin& p) { return p.link == link; }) == 0) {
    throw SessionError("link", "link '" + model_->link_name[link] + "' is not pinned");
  }
  commit(before, "unpin " + model_->link_name[link]);
}

void Session::move_pin(int link,
                       const core::Vector3& target_W,
                       const std::optional<core::Quaternion>& rotation) {
  check_link(link);
  if (!finite(target_W)) throw SessionError("target_W", "must be 3 finite numbers");
  if (rotation && (!rotation->coeffs().allFinite() || std::abs(rotation->norm() - 1) > 1e-3)) {
    throw SessionError("rotation", "must be a unit quaternion [w, x, y, z]");
  }
  const auto it = std::find_if(doc_.pins.begin(), doc_.pins.end(),
                               [&](const Pin& p) { return p.link == link; });
  if (it == doc_.pins.end()) {
    throw SessionError("link", "link '" + model_->link_name[link] + "' is not pinned");
  }
  const Document before = doc_;
  auto& pin = doc_.pins[it - doc_.pins.begin()];
  pin.target_W = target_W;
  if (rotation) pin.target_R_W = rotation->normalized();
  // consecutive moves of one pin are one gesture, one undo entry
  // consecutive moves of one pin share an id and merge
  if (last_gesture_ != kMovePinGesture + link) last_gesture_ = kMovePinGesture + link;
  history_.record(std::make_unique<DocumentChange>(
      before, doc_, "move pin " + model_->link_name[link], last_gesture_));
  settling_ = true;
}

// --- settings ------------------------------------------------------------------------------------

void Session::set_solver_settings(const ik::SolverSettings& s) {
  if (const std::string e = ik::validate(s); !e.empty()) throw SessionError("settings", e);
  const Document before = doc_;
  doc_.settings = s;
  solver_->set_settings(s);
  commit(before, "settings");
  settling_ = true;
}

void Session::set_scene(const sim::Scene& scene) {
  const Document before = doc_;
  doc_.scene = scene;
  sync_physics(/*restart=*/false);
  commit(before, "scene effects");
}

void Session::set_edit_falloff(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0 || seconds > 60) {
    throw SessionError("seconds", "must be in [0, 60]");
  }
  const Document before = doc_;
  doc_.edit_falloff = seconds;
  commit(before, "edit falloff");
}

// --- playback and recording ----------------------------------------------------------------------

void Session::play() { playback_.playing = true; }

void Session::pause() {
  if (motion_editor_) finish_motion_edit();
  playback_.playing = false;
}

void Session::seek(double time) {
  if (!std::isfinite(time)) throw SessionError("time", "must be a finite number");
  if (motion_editor_) finish_motion_edit();
  playback_.time = std::clamp(time, 0.0, std::max(0.0, duration()));
  if (!drag_) show_animation_at(playback_.time);
}

void Session::set_loop(bool loop, double start, double end) {
  if (!std::isfinite(start) || !std::isfinite(end) || start < 0 || (end >= 0 && end < start)) {
    throw SessionError(!std::isfinite(start) || start < 0 ? "start" : "end",
                       "needs 0 <= start <= end (end < 0: the end of the animation)");
  }
  playback_.loop = loop;
  playback_.loop_start = start;
  playback_.loop_end = end;
}

void Session::set_speed(double speed) {
  if (!std::isfinite(speed) || std::abs(speed) > 100)
    throw SessionError("speed", "must be in [-100, 100]");
  playback_.speed = speed;
}

void Session::record(bool on) {
  if (on == recording_.has_value()) return;
  if (on) {
    recording_ = core::Clip{};
    recording_->frame_time = 1.0 / kDefaultClipRate;
    recording_->frames.push_back(doc_.q);
    record_clock_ = 0;
    return;
  }
  core::Clip clip = std::move(*recording_);
  recording_.reset();
  if (clip.size() >= 2) set_clip(std::move(clip), "record");
}

void Session::show_animation_at(double t) {
  if (doc_.clip) {
    sample_layered(*model_, *doc_.clip, doc_.layers, t, doc_.q);
  } else if (!doc_.keys.empty()) {
    doc_.keys.sample(*model_, t, doc_.q);
  } else {
    return;
  }
  refresh_kinematics();
}

int Session::clip_frame_at(double t) const {
  return std::clamp(static_cast<int>(std::lround(t / doc_.clip->frame_time)), 0,
                    doc_.clip->size() - 1);
}

std::pair<double, double> Session::play_range() const {
  const double length = duration();
  if (!playback_.loop) return {0.0, length};
  return {std::min(playback_.loop_start, length),
          playback_.loop_end >= 0 ? std::min(playback_.loop_end, length) : length};
}

// --- editing in motion ---------------------------------------------------------------------------

void Session::start_motion_edit() {
  ik::SolverSettings s = motion_edit_settings(doc_.clip->frame_time);
  motion_editor_.emplace(*model_, s);
  motion_edit_frame_ = clip_frame_at(playback_.time);
  motion_editor_->begin(*doc_.clip, doc_.layers, motion_edit_frame_);
}

void Session::finish_motion_edit() {
  if (!motion_editor_) return;
  auto layer = motion_editor_->finish("edit " + std::to_string(++edit_counter_), doc_.edit_falloff);
  motion_editor_.reset();
  motion_edit_frame_ = -1;
  if (layer) doc_.layers.push_back(layer);
  show_animation_at(playback_.time);
}

void Session::keep_frame_edit(int frame) {
  Eigen::VectorXd below;
  layered_frame(*model_, *doc_.clip, doc_.layers, frame, below);
  auto layer = std::make_shared<EditLayer>();
  layer->displacement.emplace_back(model_->nv);
  core::difference(*model_, below, doc_.q, layer->displacement[0]);
  if (layer->displacement[0].cwiseAbs().maxCoeff() == 0.0) return;  // nothing moved
  layer->name = "edit " + std::to_string(++edit_counter_);
  layer->first_frame = frame;
  layer->falloff = doc_.edit_falloff;
  doc_.layers.push_back(std::move(layer));
  show_animation_at(playback_.time);
}

// --- time
// ------------------------------------------------------------------------------------------

bool Session::needs_tick() const {
  return playback_.playing || drag_.has_value() || settling_ || physics_ != nullptr;
}

void Session::rebuild_problem() {
  problem_.clear();
  for (const Pin& p : doc_.pins) problem_.add(p.task(), ik::pin_priority(doc_.settings));
  if (floor_gesture_) {
    for (const Pin& p : floor_->pins()) problem_.add(p.task(), ik::pin_priority(doc_.settings));
  }
  if (drag_ && gesture_before_ && doc_.settings.reference_gain > 0) {
    // the posture the gesture began in, as a preference (Yamane eq. 8.22): what the drag and
    // the pins do not need keeps its shape. "Rest gain" in the page is its gain.
    ik::add_joint_references(*model_, gesture_before_->q, problem_);
    // and the root keeps its orientation, so a squat bends the knees instead of tipping the
    // pelvis and the torso on it forward with the thighs: weighted as a pin, ten times a joint
    // reference, since the hips' references would rather tip the pelvis than flex the hips
    problem_.add(ik::LinkTask{.role = ik::kReference,
                              .link = 1,
                              .target_R_W = core::Quaternion(drag_->root_R_W),
                              .mode = ik::TaskMode::kOrientation,
                              .weight = 1.0},
                 ik::kLower);
  }
  if (drag_) {
    ik::LinkTask d = drag_task();
    // feed-forward: the target's motion since the last step (Yamane eq. 8.8)
    d.velocity_W = (d.target_W - drag_->previous_target_W) / doc_.settings.dt;
    ik::add_drag(d, doc_.settings, problem_);
  }
}

ik::LinkTask Session::drag_task() const {
  ik::LinkTask d{.role = ik::kDrag,
                 .link = drag_->link,
                 .p_LinkPoint = drag_->p_LinkPoint,
                 .target_W = drag_->target_W};
  if (doc_.settings.floor) d.target_W.y() = std::max(d.target_W.y(), drag_->floor_y);
  if (drag_->rotation) {
    d.target_R_W = *drag_->rotation;
    d.mode = ik::TaskMode::kPose;
  }
  return d;
}

double Session::drag_error() const {
  const ik::TaskError e = ik::link_task_error(data_, drag_task());
  constexpr double kMetresPerRadian = 0.1;  // a hand's length: a radian off weighs as 10 cm
  return e.position + kMetresPerRadian * e.orientation;
}

void Session::rest_when_out_of_reach(bool target_moved) {
  // a drag whose target stays put and whose error stopped shrinking has reached what it can: the
  // figure rests at the pose that came nearest, instead of cycling (at an out-of-reach target
  // with the arm straight, the references bend the elbow and the drag straightens it again, a
  // cycle at the step limit). A target that moves again starts afresh.
  constexpr double kProgress = 1e-5;  // m: less than this over kStallFrames is no progress
  constexpr int kStallFrames = 15;    // a quarter of a second at 60 Hz
  const double error = drag_error();
  if (target_moved || error < drag_->best_error - kProgress) {
    drag_->best_error = error;
    drag_->best_q = doc_.q;
    drag_->frames_without_progress = 0;
    return;
  }
  if (++drag_->frames_without_progress < kStallFrames) return;
  doc_.q = drag_->best_q;
  refresh_kinematics();
}

void Session::touch_floor() {
  if (!doc_.settings.floor) {
    floor_gesture_ = false;
    return;
  }
  floor_skips_.assign(model_->njoints, 0);
  for (const Pin& p : doc_.pins) floor_skips_[p.link] = 1;
  if (drag_) floor_skips_[drag_->link] = 1;
  if (!floor_gesture_) {
    floor_->begin(data_, floor_skips_);
    floor_gesture_ = true;
  }
}

bool Session::went_under_floor() {
  if (!floor_gesture_) return false;
  bool under = floor_->catch_penetrations(data_, floor_skips_);
  if (drag_) {
    const double depth = floor_->depth(data_, drag_->link);
    if (depth > 0) {
      // the dragged link met the floor: its point goes no lower than where it is, lifted back
      const double point_y = (data_.X_W[drag_->link] * drag_->p_LinkPoint).y();
      drag_->floor_y = std::max(drag_->floor_y, point_y + depth);
      under = true;
    }
  }
  return under;
}

bool Session::solve_step() {
  touch_floor();
  rebuild_problem();
  if (!problem_.active()) {
    settling_ = false;
    floor_gesture_ = false;
    return false;
  }
  frame_start_q_ = doc_.q;
  const bool drag_target_moved =
      drag_ && (drag_task().target_W - drag_->previous_target_W).norm() > 0.0;
  solver_->step(problem_, data_, doc_.q);
  if (drag_) drag_->previous_target_W = drag_task().target_W;
  // links the step carried below the floor are held on it, and lifted back within this frame
  bool went_under = false;
  for (int k = 0; k < kFloorCorrections && went_under_floor(); ++k) {
    went_under = true;
    rebuild_problem();
    solver_->step(problem_, data_, doc_.q);
  }
  // hard pins are brought back within a tenth of a millimetre before the frame is shown
  if (pin_hold_->hold(doc_.settings, problem_, data_, doc_.q).corrections > 0) {
    solver_->refresh_report(problem_, data_, doc_.q);  // the readouts show the corrected pose
  }
  if (drag_) rest_when_out_of_reach(drag_target_moved);
  // keep ticking while anything still moves noticeably (pins recovering after a drag). The
  // frame's net motion counts, not a step's: a step and the pins' correction may undo each
  // other on every frame of a figure at rest.
  constexpr double kRestSpeed = 1e-3;  // rad/s: under 2e-5 rad per frame, invisible
  const double frame_speed =
      (doc_.q - frame_start_q_).cwiseAbs().maxCoeff() / std::max(doc_.settings.dt, 1e-9);
  settling_ = drag_.has_value() || went_under || frame_speed > kRestSpeed;
  if (!settling_) floor_gesture_ = false;  // the gesture has come to rest
  return true;
}

void Session::edit_in_motion(double t, TickResult& result) {
  // solve every clip frame the clock passed since the last tick
  const int frame = clip_frame_at(t);
  const ik::LinkTask d = drag_task();
  if (frame < motion_edit_frame_) {
    // the clock wrapped to the loop's start: the frames up to the loop's end are solved, and the
    // same edit goes on from the start, so one gesture makes one layer however many times the
    // loop comes round
    const auto [start, end] = play_range();
    for (int f = motion_edit_frame_ + 1; f <= clip_frame_at(end); ++f) {
      motion_editor_->edit(*doc_.clip, doc_.layers, f, doc_.pins, d);
    }
    motion_edit_frame_ = std::min(clip_frame_at(start), frame) - 1;
  }
  for (int f = motion_edit_frame_ + 1; f <= frame; ++f) {
    motion_editor_->edit(*doc_.clip, doc_.layers, f, doc_.pins, d);
  }
  if (frame > motion_edit_frame_) motion_edit_frame_ = frame;
  doc_.q = motion_editor_->pose();
  refresh_kinematics();
  result.report = &motion_editor_->report();
}

Session::TickResult Session::tick(double dt) {
  TickResult result;
  if (!std::isfinite(dt) || dt < 0) dt = 0;
  const double length = duration();
  if (physics_) {
    physics_tick(dt, result);
  } else if (playback_.playing && length > 0) {
    double t = playback_.time + dt * playback_.speed;
    const auto [start, end] = play_range();
    if (playback_.loop && end > start) {
      if (t > end || t < start)
        t = start + std::fmod(std::fmod(t - start, end - start) + (end - start), end - start);
    } else if (t > length || t < 0) {
      t = std::clamp(t, 0.0, length);
      playback_.playing = false;
    }
    playback_.time = t;
    // editing in motion, or the animation as it is
    if (motion_editor_ && drag_) {
      edit_in_motion(t, result);
    } else {
      show_animation_at(t);
    }
    result.pose_changed = true;
  } else if (drag_ || settling_) {
    if (solve_step()) {
      result.report = &solver_->report();
      result.pose_changed = true;
      // the figure settling after an edit is part of that edit's undo entry
      if (!drag_) history_.amend(last_gesture_, doc_);
    }
  }
  if (recording_) {
    record_clock_ += dt;
    const std::int64_t budget = recording_frame_budget();
    while (record_clock_ >= recording_->frame_time && recording_->size() < budget) {
      recording_->frames.push_back(doc_.q);
      record_clock_ -= recording_->frame_time;
    }
    // at the clip limits the recording stops, like a tape running out, and becomes the clip
    if (recording_->size() >= budget) {
      record(false);
      result.committed = true;
    }
  }
  return result;
}

// --- undo
// ------------------------------------------------------------------------------------------

bool Session::undo() {
  if (drag_) drag_end();
  return history_.undo(*this);
}

bool Session::redo() {
  if (drag_) drag_end();
  return history_.redo(*this);
}

}  // namespace animator
