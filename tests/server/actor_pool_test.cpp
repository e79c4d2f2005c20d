// Tests for server/actor_pool.hpp: a fixed set of workers runs every job, a job never runs on two
// workers at once, a wake during a step runs it once more, deadlines run it on time and can be
// moved, and a removed job never runs again.
#include "server/actor_pool.hpp"
#include "tests/fixtures/fixtures.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace {

using server::ActorPool;
using namespace std::chrono_literals;

using fixtures::eventually;

// A job that counts its steps, records which threads ran it and whether two steps overlapped.
class CountingJob : public ActorPool::Job {
 public:
  explicit CountingJob(std::chrono::microseconds work = 0us) : work_(work) {}
  void step() override {
    if (inside_.exchange(true)) overlapped = true;
    {
      std::lock_guard lock(mutex_);
      threads_.insert(std::this_thread::get_id());
    }
    if (work_.count() > 0) std::this_thread::sleep_for(work_);
    if (on_step) on_step();
    ++steps;
    inside_ = false;
  }
  std::set<std::thread::id> threads() const {
    std::lock_guard lock(mutex_);
    return threads_;
  }
  std::atomic<int> steps{0};
  std::atomic<bool> overlapped{false};
  std::function<void()> on_step;

 private:
  std::chrono::microseconds work_;
  std::atomic<bool> inside_{false};
  mutable std::mutex mutex_;
  std::set<std::thread::id> threads_;
};

TEST(ActorPool, ManyJobsRunOnTheFixedWorkersAndNoJobOverlapsItself) {
  ActorPool pool(3);
  EXPECT_EQ(pool.threads(), 3u);
  std::vector<std::unique_ptr<CountingJob>> jobs;
  for (int i = 0; i < 40; ++i) jobs.push_back(std::make_unique<CountingJob>(100us));
  // every job is woken from several threads at once, many times
  std::vector<std::thread> wakers;
  for (int t = 0; t < 4; ++t) {
    wakers.emplace_back([&] {
      for (int round = 0; round < 50; ++round)
        for (auto& job : jobs) pool.wake(job.get());
    });
  }
  for (auto& waker : wakers) waker.join();
  ASSERT_TRUE(eventually([&] { return pool.jobs() == 0; }));
  std::set<std::thread::id> workers;
  for (auto& job : jobs) {
    EXPECT_GE(job->steps.load(), 1);
    EXPECT_FALSE(job->overlapped.load());
    for (const auto id : job->threads()) workers.insert(id);
  }
  EXPECT_LE(workers.size(), 3u);
  for (auto& job : jobs) pool.remove(job.get());
}

TEST(ActorPool, AWakeDuringAStepRunsTheJobOnceMore) {
  ActorPool pool(2);
  CountingJob job(20ms);
  pool.wake(&job);
  ASSERT_TRUE(eventually([&] { return job.threads().size() == 1; }));  // the first step runs
  for (int i = 0; i < 5; ++i) pool.wake(&job);  // all while it runs: one more step, not five
  ASSERT_TRUE(eventually([&] { return pool.jobs() == 0; }));
  EXPECT_EQ(job.steps.load(), 2);
  EXPECT_FALSE(job.overlapped.load());
}

TEST(ActorPool, ADeadlineRunsTheJobThenAndANewDeadlineReplacesTheOld) {
  ActorPool pool(2);
  CountingJob job;
  const auto start = ActorPool::Clock::now();
  std::atomic<std::int64_t> ran_after_us{-1};
  job.on_step = [&] {
    ran_after_us =
        std::chrono::duration_cast<std::chrono::microseconds>(ActorPool::Clock::now() - start)
            .count();
  };
  pool.wake_at(&job, start + 500ms);
  pool.wake_at(&job, start + 30ms);  // replaces the 500 ms one
  ASSERT_TRUE(eventually([&] { return job.steps.load() == 1; }));
  EXPECT_GE(ran_after_us.load(), 30000);
  EXPECT_LT(ran_after_us.load(), 400000);
  std::this_thread::sleep_for(600ms);
  EXPECT_EQ(job.steps.load(), 1);  // the replaced deadline never fires

  pool.wake_at(&job, ActorPool::Clock::now() + 50ms);
  pool.wake_at(&job, std::nullopt);  // no deadline any more
  std::this_thread::sleep_for(150ms);
  EXPECT_EQ(job.steps.load(), 1);
  EXPECT_EQ(pool.jobs(), 0u);
}

// wake_at wakes no worker when one already sleeps until an earlier time. That worker may then be
// woken for a long step instead: another one must take over the deadlines, or they wait for the
// step. The steps below make the worker that watches the deadlines the one a wake picks when
// sleeping workers are woken in the order they slept (glibc's do so; it is not specified, so the
// test passes either way when the pool is right).
TEST(ActorPool, DeadlinesFireOnTimeWhileTheWorkerThatWatchedThemRunsALongStep) {
  for (int round = 0; round < 3; ++round) {
    ActorPool pool(2);
    CountingJob watched, quick, later, blocking;
    std::atomic<bool> release{false};
    blocking.on_step = [&] {
      while (!release) std::this_thread::sleep_for(1ms);
    };
    const auto start = ActorPool::Clock::now();
    std::this_thread::sleep_for(5ms);       // both workers sleep without a deadline
    pool.wake_at(&watched, start + 200ms);  // one of them now sleeps until then
    std::this_thread::sleep_for(5ms);
    pool.wake_at(&watched, std::nullopt);  // it still does, with no deadline left
    pool.wake(&quick);                     // the other runs a step, sleeps again
    ASSERT_TRUE(eventually([&] { return quick.steps.load() == 1; }));
    std::this_thread::sleep_for(5ms);
    pool.wake_at(&later, start + 300ms);  // after 200 ms: nobody is woken for it
    pool.wake(&blocking);                 // the first sleeper is taken for this
    const bool fired = eventually([&] { return later.steps.load() == 1; });
    const bool still_blocked = blocking.steps.load() == 0;
    release = true;
    ASSERT_TRUE(fired) << "round " << round << ": the deadline waited for the long step";
    EXPECT_TRUE(still_blocked) << "round " << round;
    EXPECT_GE(ActorPool::Clock::now() - start, 300ms);
    ASSERT_TRUE(eventually([&] { return blocking.steps.load() == 1; }));
    EXPECT_EQ(watched.steps.load(), 0);
  }
}

TEST(ActorPool, RemoveWaitsForTheStepInProgressAndTheJobNeverRunsAgain) {
  ActorPool pool(2);
  CountingJob job(50ms);
  pool.wake(&job);
  ASSERT_TRUE(eventually([&] { return job.threads().size() == 1; }));
  pool.wake(&job);                                      // would run it again after this step
  pool.wake_at(&job, ActorPool::Clock::now() + 100ms);  // and at a deadline
  pool.remove(&job);
  EXPECT_EQ(job.steps.load(), 1);  // the step in progress finished before remove returned
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(job.steps.load(), 1);
  EXPECT_EQ(pool.jobs(), 0u);
}

TEST(ActorPool, AStepMayRemoveItsOwnJob) {
  ActorPool pool(1);
  CountingJob job;
  job.on_step = [&] {
    pool.wake_at(&job, ActorPool::Clock::now() + 10ms);
    pool.remove(&job);  // does not wait for itself
  };
  pool.wake(&job);
  ASSERT_TRUE(eventually([&] { return job.steps.load() == 1; }));
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(job.steps.load(), 1);
  EXPECT_EQ(pool.jobs(), 0u);
}

TEST(ActorPool, RunHereIfIdleRunsTheStepOnTheCallingThreadUnlessAWorkerHasIt) {
  ActorPool pool(2);
  CountingJob job;
  ASSERT_TRUE(pool.run_here_if_idle(&job));
  EXPECT_EQ(job.steps.load(), 1);
  EXPECT_EQ(job.threads(), std::set<std::thread::id>{std::this_thread::get_id()});
  EXPECT_EQ(pool.jobs(), 0u);

  // a wake that arrives during a step run here makes a worker run it once more
  std::atomic<bool> woke{false};
  job.on_step = [&] {
    if (!woke.exchange(true)) pool.wake(&job);
  };
  ASSERT_TRUE(pool.run_here_if_idle(&job));
  ASSERT_TRUE(eventually([&] { return job.steps.load() == 3 && pool.jobs() == 0; }));
  EXPECT_EQ(job.threads().size(), 2u);  // this thread and a worker

  // while a worker runs the job, the caller does not: the job never overlaps itself
  CountingJob slow(50ms);
  pool.wake(&slow);
  ASSERT_TRUE(eventually([&] { return slow.threads().size() == 1; }));
  EXPECT_FALSE(pool.run_here_if_idle(&slow));
  ASSERT_TRUE(eventually([&] { return pool.jobs() == 0; }));
  EXPECT_EQ(slow.steps.load(), 1);
  EXPECT_EQ(slow.threads().count(std::this_thread::get_id()), 0u);
  EXPECT_FALSE(slow.overlapped.load());
  pool.remove(&slow);
  pool.remove(&job);
}

TEST(ActorPool, ZeroThreadsMeansOnePerCoreAndAtLeastTwo) {
  ActorPool pool(0);
  EXPECT_GE(pool.threads(), 2u);
  EXPECT_GE(pool.threads(), std::thread::hardware_concurrency());
}

}  // namespace
