// A fixed set of worker threads that runs the session actors' steps, instead of a thread per
// session: a server with hundreds of sessions runs on as many threads as the machine has cores.
//
// A job (a SessionActor) is woken when work arrives for it, or at a deadline it asks for (its next
// solver tick). Each job runs on at most one worker at a time, and a wake that arrives while it
// runs makes it run once more afterwards, so nothing posted is left waiting. A step must not
// block on another job (it would hold a worker the other job may need).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <utility>
#include <vector>

namespace server {

class ActorPool {
 public:
  using Clock = std::chrono::steady_clock;

  /// Something the pool runs: one step does the work that is ready and returns.
  class Job {
   public:
    virtual ~Job() = default;
    virtual void step() = 0;
  };

  /// `threads` workers; 0: one per hardware thread (at least 2).
  explicit ActorPool(unsigned threads = 0);
  /// Joins the workers; every job must have been removed.
  ~ActorPool();
  ActorPool(const ActorPool&) = delete;
  ActorPool& operator=(const ActorPool&) = delete;

  /// The pool the server's sessions share when nobody passes one (sized to the machine).
  static std::shared_ptr<ActorPool> shared();

  /// Runs `job` as soon as a worker is free (once, however many wakes arrive before it runs).
  void wake(Job* job);
  /// Runs `job` at `when` unless it runs earlier; replaces the deadline it had. nullopt: none.
  void wake_at(Job* job, std::optional<Clock::time_point> when);
  /// Runs one step of `job` on the calling thread now, as a worker would, when no worker has it
  /// queued or running; returns false without running it otherwise. A wake that arrives while it
  /// runs makes a worker run it once more afterwards. For callers that hand a job a little work
  /// and would rather do it than pay for waking a worker (the server's I/O thread, for a drag
  /// sample): the step then delays what else that thread does.
  bool run_here_if_idle(Job* job);
  /// After this returns `job` is not running and never runs again (until woken anew). Waits for
  /// a step in progress, unless called from that step itself.
  void remove(Job* job);

  std::size_t threads() const { return workers_.size(); }
  /// Jobs the pool knows now (woken, waiting for a deadline or running).
  std::size_t jobs() const;

 private:
  struct State {
    bool queued = false;
    bool running = false;
    bool again = false;     // woken while running
    bool removing = false;  // remove() waits for its step: never started again
    std::optional<Clock::time_point> deadline;
  };

  void work();
  // runs `job` (marked running) with `lock` released, then settles its state and relocks
  void run_step(Job* job, std::unique_lock<std::mutex>& lock);
  void make_ready(Job* job, State& state);
  void forget_deadline(Job* job, State& state);

  mutable std::mutex mutex_;
  std::condition_variable ready_or_due_;
  std::condition_variable step_done_;
  std::map<Job*, State> states_;
  std::deque<Job*> ready_;
  std::set<std::pair<Clock::time_point, Job*>> deadlines_;
  // the times the sleeping workers wait until (one entry per worker in a timed wait)
  std::multiset<Clock::time_point> awaited_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace server
