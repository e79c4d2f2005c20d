// Session: one character being animated — its model, pose, pins, drag, solver settings, scene
// effects, base clip, edit layers, keyframes, playback clock, recorder and undo history.
//
// Thread contract: a Session is driven from one thread at a time (the server gives each its own
// actor); sessions share nothing but the immutable Model, so they need no locks.
//
// Edits are intents: the caller says what the user did (drag here, pin that, insert a key) and
// the session decides what changes. Every gesture (drag begin to end), pin change, key edit and
// clip edit is one undo entry.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "animator/document.hpp"
#include "animator/edit_layer.hpp"
#include "animator/floor_contacts.hpp"
#include "animator/history.hpp"
#include "animator/keyframes.hpp"
#include "animator/limits.hpp"
#include "animator/motion_editor.hpp"
#include "animator/physics_session.hpp"
#include "animator/pin.hpp"
#include "core/clip.hpp"
#include "core/data.hpp"
#include "core/model.hpp"
#include "core/skin.hpp"
#include "ik/pin_hold.hpp"
#include "ik/solver.hpp"

namespace io {
struct BvhLayout;  // io/bvh_import.hpp
}  // namespace io

namespace animator {

/// A request the session cannot carry out (unknown link, bad number; nothing to undo is not an
/// error). field() names the argument at fault as the Session functions below declare it
/// ("link", "target_W", "p_LinkPoint", "rotation", "index", "time", ...), empty when no single
/// argument is; what() is "<field>: <rule>". The session knows no wire protocol: the server maps
/// these fields to its message fields.
class SessionError : public std::runtime_error {
 public:
  /// A whole message without a field (file readers put a JSON path in it).
  using std::runtime_error::runtime_error;
  SessionError(std::string field, const std::string& rule)
      : std::runtime_error(field + ": " + rule), field_(std::move(field)) {}
  const std::string& field() const { return field_; }
  /// what() without the "<field>: " prefix.
  std::string rule() const {
    return std::string(what()).substr(field_.empty() ? 0 : field_.size() + 2);
  }

 private:
  std::string field_;
};

/// A request refused because it would take the session past one of its Limits; what() names the
/// limit and the setting that changes it.
class BudgetError : public SessionError {
 public:
  using SessionError::SessionError;
};

/// Frame rate of recordings and of clips made from keys.
constexpr double kDefaultClipRate = 30.0;

struct Playback {
  double time = 0;   // seconds
  double speed = 1;  // playback rate (may be negative: backwards)
  bool playing = false;
  bool loop = true;
  double loop_start = 0;
  double loop_end = -1;  // < 0: the end of the animation
  bool operator==(const Playback&) const = default;
};

class Session {
 public:
  Session(std::shared_ptr<const core::Model> model, std::string character);

  const core::Model& model() const { return *model_; }
  std::shared_ptr<const core::Model> model_ptr() const { return model_; }
  const std::string& character() const { return character_; }

  // --- budgets (animator/limits.hpp) ---------------------------------------------------------
  /// Sets the budgets every later edit is held to (what the session holds already is kept) and
  /// the undo history's byte budget. @throws SessionError when a limit is not usable
  void set_limits(const Limits& limits);
  const Limits& limits() const { return limits_; }

  // --- the pose ---------------------------------------------------------------------------
  const Eigen::VectorXd& q() const { return doc_.q; }
  /// World poses of all links for the current pose.
  const core::Data& kinematics() const { return data_; }
  /// Sets the pose (one undo entry). @throws SessionError if q is not a valid configuration
  void set_pose(const Eigen::VectorXd& q);

  // --- dragging: one undo entry per gesture -------------------------------------------------
  /// Grabs point p_LinkPoint (link frame) of `link`; the target starts at target_W. During
  /// playback this starts editing in motion. @throws BudgetError when that would make an edit
  /// layer beyond Limits::max_layers
  void drag_begin(int link,
                  const core::Vector3& target_W,
                  const core::Vector3& p_LinkPoint = core::Vector3::Zero());
  /// Moves the drag target (absolute, world). A rotation makes it a pose drag.
  void drag_move(const core::Vector3& target_W,
                 const std::optional<core::Quaternion>& rotation = std::nullopt);
  void drag_end();
  bool dragging() const { return drag_.has_value(); }
  std::optional<int> dragged_link() const;

  // --- pins ---------------------------------------------------------------------------------
  /// Pins a link where it is now (replacing a pin on the same link).
  void pin(int link, ik::TaskMode mode, const core::Vector3& p_LinkPoint = core::Vector3::Zero());
  void unpin(int link);
  /// Moves a pin's target.
  void move_pin(int link,
                const core::Vector3& target_W,
                const std::optional<core::Quaternion>& rotation = std::nullopt);
  const std::vector<Pin>& pins() const { return doc_.pins; }

  // --- settings ------------------------------------------------------------------------------
  void set_solver_settings(const ik::SolverSettings& settings);
  const ik::SolverSettings& solver_settings() const { return doc_.settings; }
  /// The effects to simulate (one undo entry). When one moves the figure (simulates()), physics
  /// starts at the current pose and the ticks advance the world instead of the solver; when none
  /// does any more, posing is kinematic again from the pose physics left.
  void set_scene(const sim::Scene& scene);
  const sim::Scene& scene() const { return doc_.scene; }
  /// The simulated world while physics runs, else nullptr.
  PhysicsSession* physics() { return physics_.get(); }
  const PhysicsSession* physics() const { return physics_.get(); }
  void set_edit_falloff(double seconds);
  double edit_falloff() const { return doc_.edit_falloff; }

  // --- keyframes -------------------------------------------------------------------------------
  /// Keys the current pose at time t (default: the playback time). Returns its index.
  /// @throws BudgetError past Limits::max_clip_seconds, or for a new key beyond max_keys
  int key_insert(std::optional<double> time = std::nullopt,
                 Interpolation interpolation = Interpolation::kSmooth);
  void key_delete(int index);
  int key_move(int index, double time);
  void key_set_interpolation(int index, Interpolation interpolation);
  const KeyTrack& keys() const { return doc_.keys; }
  /// Samples the keys into the base clip at `rate` frames per second (one undo entry).
  /// @throws BudgetError when that clip would exceed the clip limits (nothing is sampled)
  void bake_keys(double rate = kDefaultClipRate);

  // --- clips and edit layers -------------------------------------------------------------------
  /// Replaces the base clip (an import or a recording). Its model must be this session's.
  /// `markers`: the measured markers of the trial the clip was fitted to (one row per frame, at
  /// its rate), kept with it until another clip replaces it; null for any other clip.
  /// @throws BudgetError when the clip exceeds the clip limits
  /// @throws SessionError when the markers do not fit the clip
  void set_clip(core::Clip clip,
                const std::string& label = "set clip",
                std::shared_ptr<const ClipMarkers> markers = nullptr);
  const core::Clip* clip() const { return doc_.clip.get(); }
  /// The markers of the trial the clip was fitted to, or null.
  const ClipMarkers* clip_markers() const { return doc_.markers.get(); }
  const LayerStack& layers() const { return doc_.layers; }
  void set_layer_muted(int index, bool muted);
  void set_layer_weight(int index, double weight);
  void remove_layer(int index);
  /// Applies every unmuted layer to the base clip and drops the layers.
  void bake_layers();
  /// The animation as one clip: the layered base clip, else the keys sampled at the clip rate,
  /// else the current pose as a single frame.
  /// @throws BudgetError when it has more frames than the clip limits allow (a session restored
  ///         from a file made under other limits): ask for a range of frames instead
  core::Clip animation_clip() const;
  /// Frames [first, last] of animation_clip(), sampled from the clip, layers and keys directly.
  /// @throws SessionError for a range outside [0, animation_frames()), BudgetError for a range
  ///         longer than the clip limits allow
  core::Clip animation_clip(std::int64_t first, std::int64_t last) const;
  /// How many frames animation_clip() has, without building it.
  std::int64_t animation_frames() const;
  /// Seconds between the frames of animation_clip().
  double animation_frame_time() const;
  /// Frame f of animation_clip(), bit for bit, without building the clip: one layered clip
  /// frame or one sample of the keys. @throws SessionError when f is not a frame of it
  void animation_frame(std::int64_t f, Eigen::VectorXd& q_out) const;
  /// Duration of the animation (clip, else keys).
  double duration() const;

  // --- playback and recording --------------------------------------------------------------
  void play();
  void pause();
  void seek(double time);
  void set_loop(bool loop, double start = 0, double end = -1);
  void set_speed(double speed);
  const Playback& playback() const { return playback_; }
  /// Starts or stops recording: while on, the posed figure is sampled at the clip rate; stopping
  /// makes the recording the base clip (one undo entry).
  void record(bool on);
  bool recording() const { return recording_.has_value(); }

  // --- undo ---------------------------------------------------------------------------------
  bool undo();
  bool redo();
  const History& history() const { return history_; }

  // --- taking an edit back (one that could not be saved) ---------------------------------------
  /// The undo history and edit counters as they are now.
  struct Checkpoint {
    History::Checkpoint history;
    int gesture_counter = 0, last_gesture = 0, edit_counter = 0;
  };
  Checkpoint checkpoint() const;
  /// Returns to `doc` and `playback` (a state known to be saved) with the undo history of
  /// `checkpoint`: a gesture, motion edit or recording in progress ends without being kept, and
  /// playback pauses. @throws SessionError if doc.q is not a valid configuration
  void roll_back(const Document& doc, const Playback& playback, Checkpoint checkpoint);

  // --- time ---------------------------------------------------------------------------------
  struct TickResult {
    bool pose_changed = false;
    const ik::Report* report = nullptr;  // when the solver ran
    bool committed = false;  // an edit was committed: a recording stopped at the clip budget
  };
  /// Advances by dt seconds of wall time: playback, the solver while something moves, the
  /// recorder. Cheap when nothing moves. While physics runs, the world advances instead of the
  /// solver and of playback (the playback clock waits).
  TickResult tick(double dt);
  /// True while a tick would change something (playing, dragging, pins still settling, physics
  /// running).
  bool needs_tick() const;

  // --- the document (what edits change; what undo restores; what is saved) -------------------
  const Document& document() const { return doc_; }
  /// Replaces the whole document (a loaded session). Clears the history.
  void restore(Document doc, const Playback& playback);

  /// An optional skinned mesh to draw and export with the character.
  void set_skin(std::shared_ptr<const core::SkinnedMesh> skin) { skin_ = std::move(skin); }
  const core::SkinnedMesh* skin() const { return skin_.get(); }
  /// The BVH file the character came from: its joint names, channel orders and unit, which BVH
  /// exports keep by default (io/bvh_writer.hpp). Null for other characters. Not an edit: undo
  /// leaves it, and it is saved with the character.
  void set_bvh_source(std::shared_ptr<const io::BvhLayout> source) {
    bvh_source_ = std::move(source);
  }
  const std::shared_ptr<const io::BvhLayout>& bvh_source() const { return bvh_source_; }

 private:
  friend class DocumentChange;
  void check_link(int link) const;
  void commit(const Document& before, const std::string& label);
  void apply_document(const Document& doc);
  void refresh_kinematics();
  void rebuild_problem();
  ik::LinkTask drag_task() const;
  /// Starts or stops physics as the document's scene asks; `restart`: a running world begins
  /// again at the document's pose (it was replaced).
  void sync_physics(bool restart);
  void physics_tick(double dt, TickResult& result);
  bool solve_step();
  /// The dragged point's distance from its target (plus 0.1 m per radian in pose mode).
  double drag_error() const;
  /// Holds the figure at the pose nearest the target once a still drag stops making progress.
  void rest_when_out_of_reach(bool target_moved);
  /// Before a step: starts the gesture's floor contacts if it has none (settings.floor).
  void touch_floor();
  /// After a step: holds links that went below the floor on it; true when any did.
  bool went_under_floor();
  /// Extra solver steps a frame takes to lift links that went below the floor back onto it.
  static constexpr int kFloorCorrections = 2;
  void show_animation_at(double t);
  /// The clip frame nearest clip time t.
  int clip_frame_at(double t) const;
  /// The times playback runs between: the loop's [start, end] when looping, else the animation.
  std::pair<double, double> play_range() const;
  void start_motion_edit();
  void finish_motion_edit();
  /// The pose a drag left at a paused clip's frame, kept as a one-frame layer with the falloff.
  void keep_frame_edit(int frame);
  /// One tick of editing in motion at clip time t: every frame the clock passed is solved.
  void edit_in_motion(double t, TickResult& result);
  void check_key_time(double time) const;
  void check_clip_budget(std::int64_t frames, double frame_time, const std::string& field) const;
  std::int64_t recording_frame_budget() const;

  std::shared_ptr<const core::Model> model_;
  std::string character_;
  std::shared_ptr<const core::SkinnedMesh> skin_;
  std::shared_ptr<const io::BvhLayout> bvh_source_;
  Document doc_;
  Playback playback_;
  History history_;
  Limits limits_;

  // the live gesture
  struct Drag {
    int link = 0;
    core::Vector3 p_LinkPoint = core::Vector3::Zero();
    core::Vector3 target_W = core::Vector3::Zero();
    std::optional<core::Quaternion> rotation;
    core::Vector3 previous_target_W = core::Vector3::Zero();  // as solved (the floor applied)
    core::Matrix3 root_R_W = core::Matrix3::Identity();       // the root's orientation at the start
    // with the floor on, the dragged point is kept at or above this height: where it was when
    // the dragged link's shapes met the floor
    double floor_y = -std::numeric_limits<double>::infinity();
    // a drag over a paused clip edits the frame shown; its end keeps the edit as a layer
    int edit_frame = -1;
    // the pose that came nearest the (still) target, and how long the drag has not improved on it
    double best_error = std::numeric_limits<double>::infinity();
    Eigen::VectorXd best_q;
    int frames_without_progress = 0;
  };
  std::optional<Drag> drag_;
  std::optional<Document> gesture_before_;
  std::optional<MotionEditor> motion_editor_;  // while dragging during playback
  int motion_edit_frame_ = -1;

  // recording
  std::optional<core::Clip> recording_;
  double record_clock_ = 0;

  // physics, while the scene simulates (animator/session_physics.cpp)
  std::unique_ptr<PhysicsSession> physics_;

  // solver state
  core::Data data_;
  ik::Problem problem_;
  std::unique_ptr<ik::Solver> solver_;
  std::unique_ptr<ik::PinHold>
      pin_hold_;                   // hard pins held to a tenth of a millimetre after every step
  Eigen::VectorXd frame_start_q_;  // the pose before this frame's solver step
  bool settling_ = false;
  // the floor in kinematic posing (settings.floor): contacts held for the gesture being solved
  std::unique_ptr<FloorContacts> floor_;
  bool floor_gesture_ = false;     // floor_ holds this gesture's contacts
  std::vector<char> floor_skips_;  // links the floor leaves alone: dragged or pinned by the user
  int edit_counter_ = 0;
  int gesture_counter_ = 0;  // ids of committed edits
  int last_gesture_ = 0;     // the newest edit, which settling amends
};

}  // namespace animator
