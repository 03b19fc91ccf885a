#pragma once
/// @file
/// A set of worker threads shared by coarse jobs (one joint's tuning) and the fine tasks a job
/// fans out (its nonlinear stage's simulations). `fullarm tune` runs each joint's linear stage and
/// then its nonlinear stage as one job: a worker takes the next job as soon as it is free, and a
/// worker that finds no job left helps the jobs still running with their simulations instead of
/// idling (docs/analysis.md, "Scheduling of tune"). Which thread runs what depends on timing;
/// the callers make the results independent of it (the nonlinear stage takes its runs in set order
/// and sizes its blocks by available(), which changes only how many runs are simulated ahead).
/// Offline (allocates, locks), not @rt.

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace fullarm::core {

/// Worker threads for coarse jobs and the fine tasks they fan out.
class JobPool {
 public:
  /// Starts one worker thread running `body`; throws std::system_error when the system cannot
  /// (std::thread's own contract). The default starts a std::thread.
  using ThreadStarter = std::function<std::thread(std::function<void()> body)>;

  /// @param threads worker threads including the caller of run() (>= 1).
  /// @param start_thread how run() starts its workers (empty: std::thread); a seam for the test of
  ///        a system that refuses threads.
  /// @throws std::invalid_argument when threads < 1.
  explicit JobPool(int threads, ThreadStarter start_thread = {});
  JobPool(const JobPool&) = delete;
  JobPool& operator=(const JobPool&) = delete;
  ~JobPool() = default;

  /// Worker threads (including the caller of run()).
  [[nodiscard]] int threads() const noexcept { return threads_; }

  /// Runs job(i) for every i in [0, jobs), started in index order, each on one worker (the
  /// calling thread and threads() - 1 started ones). A worker with no job left runs the tasks
  /// other jobs fan out. Returns when every job has returned; after all have ended, rethrows the
  /// exception of the lowest-numbered job that threw (not the first in time, so the error a caller
  /// sees does not depend on the thread count or timing). Not reentrant (call it from one thread, not from a job).
  /// When the system refuses a thread (std::system_error), run() goes on with the workers it has
  /// (at least the caller): the same results, later.
  void run(int jobs, const std::function<void(int)>& job);

  /// How many threads could run a fan-out now: 1 (the caller) + the workers waiting for work.
  /// A hint (it can change at once); use it to size blocks of speculative work.
  [[nodiscard]] int available() const;

  /// Runs task(i) for every i in [0, tasks) on the calling thread and on workers that have no
  /// job; returns when all have returned; after all have ended, rethrows the exception of the
  /// lowest-numbered task that threw. Callable from a job of run() or from any thread (then the caller does all the
  /// work unless workers are idle in a run()). A task must not call fanOut() itself.
  void fanOut(int tasks, const std::function<void(int)>& task);

 private:
  struct Batch {
    const std::function<void(int)>* task = nullptr;
    int size = 0;
    int next = 0;              // next unclaimed index
    int done = 0;              // returned tasks
    std::exception_ptr error;  // of the lowest failed index
    int error_index = 0;       // its index; size while none failed
  };
  void worker();
  // Claims and runs the next task of `b`; `lock` is held on entry and on return.
  void runOneTask(Batch& b, std::unique_lock<std::mutex>& lock);

  int threads_ = 1;
  ThreadStarter start_thread_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<Batch*> open_;  // batches with unclaimed tasks, oldest first
  int idle_ = 0;              // workers waiting in worker()
  const std::function<void(int)>* job_ = nullptr;
  int jobs_ = 0;
  int next_job_ = 0;
  int jobs_done_ = 0;
  std::exception_ptr job_error_;  // of the lowest failed job
  int job_error_index_ = 0;       // its index; jobs_ while none failed
};

}  // namespace fullarm::core
