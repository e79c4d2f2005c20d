#include "server/actor_pool.hpp"

#include <algorithm>
#include <exception>
#include <iostream>

namespace server {

namespace {

thread_local const ActorPool::Job* t_running_job = nullptr;  // the step this worker runs

}  // namespace

ActorPool::ActorPool(unsigned threads) {
  if (threads == 0) threads = std::max(2u, std::thread::hardware_concurrency());
  workers_.reserve(threads);
  for (unsigned i = 0; i < threads; ++i) workers_.emplace_back([this] { work(); });
}

ActorPool::~ActorPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  ready_or_due_.notify_all();
  for (auto& worker : workers_) worker.join();
}

std::shared_ptr<ActorPool> ActorPool::shared() {
  static const auto pool = std::make_shared<ActorPool>();
  return pool;
}

std::size_t ActorPool::jobs() const {
  std::lock_guard lock(mutex_);
  return states_.size();
}

void ActorPool::wake(Job* job) {
  std::lock_guard lock(mutex_);
  make_ready(job, states_[job]);
}

void ActorPool::wake_at(Job* job, std::optional<Clock::time_point> when) {
  {
    std::lock_guard lock(mutex_);
    State& state = states_[job];
    if (state.removing) return;
    forget_deadline(job, state);
    if (!when) {
      if (!state.queued && !state.running) states_.erase(job);
      return;
    }
    state.deadline = when;
    deadlines_.emplace(*when, job);
    // a worker already sleeping until an earlier time sees this deadline when it wakes: waking
    // one now would put a thread on a core for nothing, on every step of a moving session
    if (!awaited_.empty() && *awaited_.begin() <= *when) return;
  }
  ready_or_due_.notify_one();  // no worker waits for a time this early: wake one
}

void ActorPool::remove(Job* job) {
  std::unique_lock lock(mutex_);
  if (const auto it = states_.find(job); it != states_.end()) it->second.removing = true;
  if (t_running_job != job) {
    step_done_.wait(lock, [&] {
      const auto it = states_.find(job);
      return it == states_.end() || !it->second.running;
    });
  }
  const auto it = states_.find(job);
  if (it == states_.end()) return;
  if (it->second.queued) ready_.erase(std::find(ready_.begin(), ready_.end(), job));
  forget_deadline(job, it->second);
  states_.erase(it);
}

bool ActorPool::run_here_if_idle(Job* job) {
  std::unique_lock lock(mutex_);
  if (const auto it = states_.find(job); it != states_.end()) {
    const State& state = it->second;
    if (state.queued || state.running || state.removing) return false;
  }
  states_[job].running = true;
  run_step(job, lock);
  return true;
}

void ActorPool::run_step(Job* job, std::unique_lock<std::mutex>& lock) {
  lock.unlock();
  const Job* outer = std::exchange(t_running_job, job);
  try {
    job->step();
  } catch (const std::exception& e) {
    std::cerr << "pindrag serve: a session step failed: " << e.what() << "\n";
  }
  t_running_job = outer;
  lock.lock();
  const auto it = states_.find(job);  // gone when the step removed its own job
  if (it != states_.end()) {
    State& after = it->second;
    after.running = false;
    if (std::exchange(after.again, false)) {
      make_ready(job, after);
    } else if (!after.queued && !after.deadline) {
      states_.erase(it);
    }
  }
  step_done_.notify_all();
}

void ActorPool::make_ready(Job* job, State& state) {
  if (state.removing) return;
  if (state.running) {
    state.again = true;
  } else if (!state.queued) {
    state.queued = true;
    ready_.push_back(job);
    ready_or_due_.notify_one();
  }
}

void ActorPool::forget_deadline(Job* job, State& state) {
  if (state.deadline) deadlines_.erase({*state.deadline, job});
  state.deadline.reset();
}

void ActorPool::work() {
  std::unique_lock lock(mutex_);
  for (;;) {
    const auto now = Clock::now();
    while (!deadlines_.empty() && deadlines_.begin()->first <= now) {
      Job* job = deadlines_.begin()->second;
      deadlines_.erase(deadlines_.begin());
      State& state = states_.at(job);
      state.deadline.reset();
      make_ready(job, state);
    }
    if (!ready_.empty()) {
      Job* job = ready_.front();
      ready_.pop_front();
      State& state = states_.at(job);
      state.queued = false;
      state.running = true;
      // while this worker runs the step, another one must watch the deadlines: wake one when no
      // worker is in a timed wait (wake_at skips waking anyone while one is)
      if (!deadlines_.empty() && awaited_.empty()) ready_or_due_.notify_one();
      run_step(job, lock);
      continue;
    }
    if (stopping_) return;
    if (deadlines_.empty()) {
      ready_or_due_.wait(lock);
    } else {
      // a copy: the set's node may be erased while this worker waits
      const Clock::time_point due = deadlines_.begin()->first;
      const auto awaiting = awaited_.insert(due);
      ready_or_due_.wait_until(lock, due);
      awaited_.erase(awaiting);
    }
  }
}

}  // namespace server
