// One actor per session: the only code that touches its animator::Session (STYLE.md §8). Its
// steps run on a shared ActorPool (server/actor_pool.hpp), one step at a time, so the number of
// threads does not grow with the number of sessions.
//
// Thread contract: every public function may be called from any thread; they only enqueue,
// except that post() of a cheap drag sample may run the step on the calling thread
// (kInlineTickBudget), so the caller must not hold a lock a step could need.
// Commands (edits, subscriptions, calls from HTTP handlers) run in the order they were posted;
// `drag_move` samples go into a latest-wins mailbox, so a burst of samples is applied as one.
// A sample is flushed into the ordered queue when a command arrives after it, so a drag_end never
// overtakes the drag_moves before it. The solver ticks only while Session::needs_tick() says
// something moves: every kTickPeriod, and immediately after a new drag sample unless the last
// sample's tick was under kMinTickInterval ago.
// A drag ends when the connection that began it unsubscribes (a client that vanished mid-drag).
//
// Durability (server/session_journal.hpp): an edit is acknowledged only once its journal record
// is on disk. When the record cannot be written (disk full, a file size limit), the edit is taken
// back (the session returns to what the disk holds, with the undo history it had), the client
// gets an `error` on the edit's id instead of an `ack`, and every connection gets the `state`
// again. A drag_move is acknowledged as applied to the gesture in progress; the gesture is
// saved with its drag_end. The settled pose after an edit is recorded when the figure comes to
// rest; snapshots are written off the actor's steps.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "animator/session.hpp"
#include "server/actor_pool.hpp"
#include "server/messages.hpp"
#include "server/protocol.hpp"
#include "server/session_journal.hpp"

namespace server {

/// A call_within() that did not complete within its timeout (HTTP: 503 with Retry-After).
class ActorBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A WebSocket connection as the actor sees it. Called from the actor's steps; must not block.
class SessionSubscriber {
 public:
  virtual ~SessionSubscriber() = default;
  /// A JSON text message; reliable and in order.
  virtual void send_text(std::string message) = 0;
  /// A binary pose frame; the connection keeps only the newest one not yet written.
  virtual void send_pose(std::string frame) = 0;
};

/// Counters for tests and the benchmark.
struct ActorStats {
  std::uint64_t ticks = 0;
  std::uint64_t drag_samples_received = 0;
  std::uint64_t drag_samples_applied = 0;
  std::uint64_t saves = 0;  // journal records written
  std::uint64_t save_failures = 0;
  std::uint64_t snapshots = 0;
  std::uint64_t pose_frames = 0;
  std::uint64_t steps_on_posting_thread = 0;    // drag samples solved by post()'s caller
  std::uint64_t sample_ticks_deferred = 0;      // steps whose sample waits for kMinTickInterval
  std::chrono::microseconds last_tick_cost{0};  // wall time of the last solver tick
};

class SessionActor : private ActorPool::Job {
 public:
  /// Smallest wall time between two ticks for drag samples (at most 500 per second, beside the
  /// periodic ticks of kTickPeriod).
  static constexpr std::chrono::microseconds kMinTickInterval{2000};
  /// Wall time between ticks while playing or settling with no new drag sample.
  static constexpr std::chrono::microseconds kTickPeriod{16667};
  /// A drag sample posted when the actor is idle with no command queued is solved on the
  /// posting thread (the server's I/O thread) if the last tick took at most this long: two
  /// thread wake-ups cost more than such a solve. Slower sessions always run on a worker.
  static constexpr std::chrono::microseconds kInlineTickBudget{250};
  /// The share of a posting thread's wall time it may spend in the steps it runs itself.
  static constexpr double kInlineShare = 0.1;

  /// `journal` null: the session is not saved. Steps run on `pool`.
  SessionActor(std::string id,
               std::unique_ptr<animator::Session> session,
               std::unique_ptr<SessionJournal> journal,
               std::shared_ptr<ActorPool> pool = ActorPool::shared());
  /// A new session saved at `save_path` (SessionJournal::start); empty: not saved.
  /// @throws animator::SessionWriteError
  SessionActor(std::string id,
               std::unique_ptr<animator::Session> session,
               const std::string& save_path,
               std::shared_ptr<ActorPool> pool = ActorPool::shared());
  ~SessionActor() override;
  SessionActor(const SessionActor&) = delete;
  SessionActor& operator=(const SessionActor&) = delete;

  const std::string& id() const { return id_; }
  /// The session's model: immutable, safe to read from any thread.
  const core::Model& model() const { return *model_; }

  /// Adds a connection: it gets the snapshot, then pose frames and `state`/`report` messages.
  void subscribe(std::uint64_t connection, std::shared_ptr<SessionSubscriber> subscriber);
  void unsubscribe(std::uint64_t connection);
  /// A decoded client message of `connection` (not `hello`): a `drag_move` goes into the
  /// mailbox, anything else on the ordered queue, to be applied by apply() (apply_message.hpp)
  /// and answered with `ack` or `error` when it has an id.
  void post(std::uint64_t connection, ClientRequest request);

  /// Runs `f` in a step of the actor and returns its result (exceptions are rethrown here).
  /// `edit`: the call may change the document; then the change is saved before the result is
  /// returned, and `state` is sent. @throws animator::SessionWriteError when it cannot be saved
  /// (the change is taken back then)
  template <class F>
  auto call(F f, bool edit = false) -> decltype(f(std::declval<animator::Session&>())) {
    using R = decltype(f(std::declval<animator::Session&>()));
    auto promise = std::make_shared<std::promise<R>>();
    auto future = promise->get_future();
    const bool accepted = enqueue_call(
        [promise, f = std::move(f)](animator::Session& s,
                                    const std::function<void()>& save) mutable {
          try {
            if constexpr (std::is_void_v<R>) {
              f(s);
              save();
              promise->set_value();
            } else {
              R result = f(s);
              save();
              promise->set_value(std::move(result));
            }
          } catch (...) {
            promise->set_exception(std::current_exception());
          }
        },
        edit);
    if (!accepted) throw animator::SessionError("session " + id_ + ": the server is shutting down");
    return future.get();
  }

  /// Callers of call_within() that may wait at once; more are refused at once, so one busy
  /// session holds at most this many HTTP threads.
  static constexpr int kMaxWaitingCallers = 4;
  /// Callers inside call_within() now, waiting or about to be refused.
  int waiting_callers() const { return waiting_callers_.load(); }

  /// call() for callers that must not wait long (HTTP handlers): returns `f`'s result if it
  /// completes within `timeout`. A call still queued when the timeout passes is withdrawn and
  /// never runs; one already running completes on the actor and its result is dropped.
  /// `f` must own what it uses (capture by value): it may run after this function returned.
  /// `edit`: as for call(), the change is saved before the result is returned.
  /// @throws ActorBusy when the timeout passes first, or kMaxWaitingCallers already wait;
  ///         animator::SessionWriteError when an edit cannot be saved (it is taken back then)
  template <class F>
  auto call_within(std::chrono::milliseconds timeout, F f, bool edit = false)
      -> decltype(f(std::declval<animator::Session&>())) {
    using R = decltype(f(std::declval<animator::Session&>()));
    if (++waiting_callers_ > kMaxWaitingCallers) {
      --waiting_callers_;
      throw ActorBusy("session " + id_ + ": " + std::to_string(kMaxWaitingCallers) +
                      " requests wait for it already; this one was not run (retry later)");
    }
    struct Leave {
      std::atomic<int>& waiting;
      ~Leave() { --waiting; }
    } leave{waiting_callers_};
    struct Pending {
      std::promise<R> promise;
      std::atomic<int> stage{0};  // 0 queued, 1 running, 2 withdrawn by the caller
    };
    auto pending = std::make_shared<Pending>();
    auto future = pending->promise.get_future();
    const bool accepted = enqueue_call(
        [pending, f = std::move(f)](animator::Session& s,
                                    const std::function<void()>& save) mutable {
          int queued = 0;
          if (!pending->stage.compare_exchange_strong(queued, 1)) return;  // the caller left
          try {
            if constexpr (std::is_void_v<R>) {
              f(s);
              save();
              pending->promise.set_value();
            } else {
              R result = f(s);
              save();
              pending->promise.set_value(std::move(result));
            }
          } catch (...) {
            pending->promise.set_exception(std::current_exception());
          }
        },
        edit);
    if (!accepted) throw animator::SessionError("session " + id_ + ": the server is shutting down");
    if (future.wait_for(timeout) != std::future_status::ready) {
      int queued = 0;
      const std::string waited = std::to_string(timeout.count()) + " ms";
      if (pending->stage.compare_exchange_strong(queued, 2)) {
        throw ActorBusy("session " + id_ + ": busy with earlier work for " + waited +
                        "; this request was not run (retry later)");
      }
      if (future.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
        throw ActorBusy("session " + id_ + ": this request is still running after " + waited +
                        " and completes in the background (retry later for its result)");
      }
    }
    return future.get();
  }

  ActorStats stats() const;
  /// Replaces kInlineTickBudget for this actor (tests: a budget every tick meets, or none).
  void set_inline_tick_budget(std::chrono::microseconds budget);
  /// Runs the commands already posted (saving if needed) on the calling thread, then stops: no
  /// step runs afterwards. Idempotent. Must not be called from a step of this actor.
  void stop();

 private:
  struct DragSample {
    std::uint64_t connection = 0;
    DragMove move;
    std::vector<nlohmann::json> ack_ids;  // ids of this sample and of those it superseded
  };
  struct Item {
    enum class Kind { kMessage, kDrag, kSubscribe, kUnsubscribe, kCall } kind = Kind::kMessage;
    std::uint64_t connection = 0;
    ClientRequest request;
    DragSample drag;
    std::shared_ptr<SessionSubscriber> subscriber;
    // runs on the session; calls `save` after changing it (a no-op unless `edit`)
    std::function<void(animator::Session&, const std::function<void()>& save)> call;
    bool edit = false;
  };

  bool enqueue_call(std::function<void(animator::Session&, const std::function<void()>& save)> f,
                    bool edit);
  bool enqueue(Item item);
  void start();
  void step() override;  // applies what was posted, ticks when due, asks for the next tick
  void process(Item& item);
  void apply_request(std::uint64_t connection, const ClientRequest& request);
  bool apply_drag(DragSample& sample);
  void tick();
  void broadcast_pose();
  void broadcast_text(const std::string& text);
  void send_to(std::uint64_t connection, std::string text);
  void after_edit();
  void save_edit(const nlohmann::json& op, animator::Session::Checkpoint checkpoint);
  void settle();

  const std::string id_;
  std::unique_ptr<animator::Session> session_;
  std::shared_ptr<const core::Model> model_;
  std::unique_ptr<SessionJournal> journal_;  // null: not saved

  // shared with posting threads
  const std::shared_ptr<ActorPool> pool_;
  mutable std::mutex mutex_;             // taken before the pool's, never after
  std::atomic<int> waiting_callers_{0};  // in call_within()
  std::deque<Item> queue_;
  std::optional<DragSample> mailbox_;
  bool stopping_ = false;
  bool tick_deferred_ = false;  // a sample's tick waits for kMinTickInterval: samples gather
  ActorStats stats_;            // its last_tick_cost decides where post() runs a sample's step
  std::chrono::microseconds inline_tick_budget_ = kInlineTickBudget;

  // the actor's steps only
  std::map<std::uint64_t, std::shared_ptr<SessionSubscriber>> subscribers_;
  std::map<std::uint64_t, std::uint32_t> last_seq_;
  std::optional<std::uint64_t> drag_owner_;  // the connection whose drag_begin is active
  std::uint32_t frame_id_ = 0;
  std::chrono::steady_clock::time_point last_tick_{};
  std::chrono::steady_clock::time_point last_sample_tick_{};  // the last tick a sample asked for
  std::chrono::steady_clock::time_point last_report_{};
  std::optional<std::string> held_report_;  // the newest report the rate limit held back
  bool was_moving_ = false;
  bool pose_dirty_ = false;
  bool tick_owed_ = false;  // a drag sample arrived since the last tick
};

}  // namespace server
