// The job pool under `fullarm tune`: every job and every fanned-out task runs exactly once for any
// thread count (brute-force counts), a worker with no job left really runs another job's tasks
// (two tasks that can only finish together), errors reach the caller (the lowest-numbered
// failure's), and bad sizes are refused.

#include "fullarm/core/job_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace fullarm::core {
namespace {

// Waits (bounded, so that a scheduling bug fails the test instead of hanging it) until `done()`.
template <typename Done>
bool waitFor(Done done) {
  const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!done()) {
    if (std::chrono::steady_clock::now() > limit) return false;
    std::this_thread::yield();
  }
  return true;
}

TEST(JobPool, EveryJobAndEveryTaskRunsExactlyOnceForAnyThreadCount) {
  constexpr int kJobs = 9;
  for (const int threads : {1, 2, 3, 5}) {
    core::JobPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    std::vector<std::atomic<int>> job_hits(kJobs);
    // Job j fans out 3 + j tasks twice (two blocks, as the nonlinear stage does).
    std::vector<std::vector<std::atomic<int>>> task_hits(kJobs);
    for (int j = 0; j < kJobs; ++j) task_hits[static_cast<std::size_t>(j)] = std::vector<std::atomic<int>>(3 + j);
    pool.run(kJobs, [&](int j) {
      ++job_hits[static_cast<std::size_t>(j)];
      auto& hits = task_hits[static_cast<std::size_t>(j)];
      for (int block = 0; block < 2; ++block) {
        EXPECT_GE(pool.available(), 1);
        EXPECT_LE(pool.available(), threads);
        pool.fanOut(static_cast<int>(hits.size()), [&](int i) { ++hits[static_cast<std::size_t>(i)]; });
      }
    });
    for (int j = 0; j < kJobs; ++j) {
      EXPECT_EQ(job_hits[static_cast<std::size_t>(j)].load(), 1) << "threads " << threads << " job " << j;
      for (const std::atomic<int>& h : task_hits[static_cast<std::size_t>(j)]) EXPECT_EQ(h.load(), 2);
    }
    // The pool can run again.
    std::atomic<int> again{0};
    pool.run(4, [&](int) { ++again; });
    EXPECT_EQ(again.load(), 4);
  }
}

// One job on two threads: the second thread has no job, so it must run task 1 while the job's own
// thread is inside task 0, which waits for task 1 to start (a sequential fan-out would never end:
// the bounded wait then fails the test).
TEST(JobPool, AWorkerWithNoJobLeftRunsTheTasksOfAnother) {
  core::JobPool pool(2);
  std::thread::id owner;
  std::thread::id helper;
  std::atomic<bool> task1_started{false};
  bool helper_was_idle = false;
  bool task0_saw_task1 = false;
  pool.run(1, [&](int) {
    owner = std::this_thread::get_id();
    helper_was_idle = waitFor([&] { return pool.available() == 2; });
    pool.fanOut(2, [&](int i) {
      if (i == 0) {
        task0_saw_task1 = waitFor([&] { return task1_started.load(); });
      } else {
        helper = std::this_thread::get_id();
        task1_started = true;
      }
    });
  });
  EXPECT_TRUE(helper_was_idle);
  EXPECT_TRUE(task0_saw_task1);
  EXPECT_NE(helper, owner);
  EXPECT_NE(helper, std::thread::id());
}

TEST(JobPool, AFanOutOutsideARunIsDoneByTheCaller) {
  core::JobPool pool(3);
  EXPECT_EQ(pool.available(), 1);
  std::vector<std::thread::id> ran(6);
  pool.fanOut(6, [&](int i) { ran[static_cast<std::size_t>(i)] = std::this_thread::get_id(); });
  for (const std::thread::id& id : ran) EXPECT_EQ(id, std::this_thread::get_id());
}

TEST(JobPool, ErrorsOfJobsAndTasksReachTheCallerAfterTheOthersEnd) {
  core::JobPool pool(2);
  std::atomic<int> finished{0};
  EXPECT_THROW(pool.run(6,
                        [&](int j) {
                          if (j == 2) throw std::runtime_error("job 2");
                          ++finished;
                        }),
               std::runtime_error);
  EXPECT_EQ(finished.load(), 5);
  // A task's error reaches the job that fanned it out; the other tasks still run.
  std::atomic<int> tasks{0};
  bool caught = false;
  pool.run(1, [&](int) {
    try {
      pool.fanOut(5, [&](int i) {
        ++tasks;
        if (i == 1) throw std::out_of_range("task 1");
      });
    } catch (const std::out_of_range&) {
      caught = true;
    }
  });
  EXPECT_TRUE(caught);
  EXPECT_EQ(tasks.load(), 5);
  EXPECT_THROW(core::JobPool(0), std::invalid_argument);
}

// The error a caller sees is the lowest-numbered failure's, not the first in time: job 1 (task 1)
// fails and its thread goes idle (available() == 2, so its error is recorded) before job 0 (task
// 0) fails. The old rule, first in time, reported job 1 and task 1.
TEST(JobPool, TheLowestNumberedFailureIsReportedWhateverTheTiming) {
  core::JobPool pool(2);
  std::atomic<bool> job1_failed{false};
  std::string message;
  try {
    pool.run(2, [&](int j) {
      if (j == 1) {
        job1_failed = true;
        throw std::runtime_error("job 1");
      }
      EXPECT_TRUE(waitFor([&] { return job1_failed.load(); }));
      EXPECT_TRUE(waitFor([&] { return pool.available() == 2; }));
      throw std::runtime_error("job 0");
    });
  } catch (const std::runtime_error& e) {
    message = e.what();
  }
  EXPECT_EQ(message, "job 0");

  std::atomic<bool> task1_failed{false};
  message.clear();
  pool.run(1, [&](int) {
    EXPECT_TRUE(waitFor([&] { return pool.available() == 2; }));  // the helper waits for tasks
    try {
      pool.fanOut(2, [&](int i) {
        if (i == 1) {
          task1_failed = true;
          throw std::runtime_error("task 1");
        }
        EXPECT_TRUE(waitFor([&] { return task1_failed.load(); }));
        EXPECT_TRUE(waitFor([&] { return pool.available() == 2; }));
        throw std::runtime_error("task 0");
      });
    } catch (const std::runtime_error& e) {
      message = e.what();
    }
  });
  EXPECT_EQ(message, "task 0");
}

// A system that refuses threads (std::system_error from the thread start, as std::thread throws
// it): run() goes on with the workers it has, down to the caller alone, and every job and task
// still runs exactly once, on no more threads than were started.
TEST(JobPool, WhenTheSystemRefusesThreadsTheWorkersStartedDoAllTheWork) {
  for (const int allowed : {0, 1}) {
    int started = 0;
    core::JobPool pool(4, [&](std::function<void()> body) {
      if (started >= allowed) throw std::system_error(std::make_error_code(std::errc::resource_unavailable_try_again));
      ++started;
      return std::thread(std::move(body));
    });
    constexpr int kJobs = 6, kTasks = 5;
    std::vector<std::atomic<int>> job_runs(kJobs), task_runs(kJobs * kTasks);
    std::mutex ids_mutex;
    std::set<std::thread::id> ids;
    pool.run(kJobs, [&](int j) {
      ++job_runs[static_cast<std::size_t>(j)];
      pool.fanOut(kTasks, [&](int t) {
        ++task_runs[static_cast<std::size_t>(j * kTasks + t)];
        const std::lock_guard<std::mutex> lock(ids_mutex);
        ids.insert(std::this_thread::get_id());
      });
    });
    for (const auto& n : job_runs) EXPECT_EQ(n.load(), 1);
    for (const auto& n : task_runs) EXPECT_EQ(n.load(), 1);
    EXPECT_EQ(started, allowed);
    EXPECT_LE(ids.size(), static_cast<std::size_t>(1 + allowed));
    if (allowed == 0) {
      EXPECT_EQ(*ids.begin(), std::this_thread::get_id());
    }
  }
}

}  // namespace
}  // namespace fullarm::core
