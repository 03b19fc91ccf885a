#include "fullarm/core/job_pool.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <utility>

namespace fullarm::core {

JobPool::JobPool(int threads, ThreadStarter start_thread) : threads_(threads), start_thread_(std::move(start_thread)) {
  if (threads < 1) throw std::invalid_argument("JobPool: expected threads >= 1, got " + std::to_string(threads));
  if (!start_thread_) {
    start_thread_ = [](std::function<void()> body) { return std::thread(std::move(body)); };
  }
}

int JobPool::available() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return 1 + idle_;
}

void JobPool::runOneTask(Batch& b, std::unique_lock<std::mutex>& lock) {
  const int i = b.next++;
  if (b.next == b.size) open_.erase(std::find(open_.begin(), open_.end(), &b));
  lock.unlock();
  std::exception_ptr error;
  try {
    (*b.task)(i);
  } catch (...) {
    error = std::current_exception();
  }
  lock.lock();
  if (error && i < b.error_index) {  // the lowest index's error, whatever the timing
    b.error = error;
    b.error_index = i;
  }
  if (++b.done == b.size) wake_.notify_all();  // the batch's owner waits for this
}

void JobPool::worker() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    if (next_job_ < jobs_) {
      const int i = next_job_++;
      lock.unlock();
      std::exception_ptr error;
      try {
        (*job_)(i);
      } catch (...) {
        error = std::current_exception();
      }
      lock.lock();
      if (error && i < job_error_index_) {  // the lowest job's error, whatever the timing
        job_error_ = error;
        job_error_index_ = i;
      }
      if (++jobs_done_ == jobs_) wake_.notify_all();
      continue;
    }
    if (!open_.empty()) {
      runOneTask(*open_.front(), lock);
      continue;
    }
    // No job left to start: once every job has returned, no fan-out can open any more.
    if (jobs_done_ == jobs_) return;
    ++idle_;
    wake_.wait(lock);
    --idle_;
  }
}

void JobPool::run(int jobs, const std::function<void(int)>& job) {
  if (jobs <= 0) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (job_ != nullptr) throw std::logic_error("JobPool::run: already running");
    job_ = &job;
    jobs_ = jobs;
    next_job_ = 0;
    jobs_done_ = 0;
    job_error_ = nullptr;
    job_error_index_ = jobs;
  }
  std::vector<std::thread> pool;
  // All threads start even with fewer jobs: the spare ones help with the jobs' fan-outs.
  const int extra = threads_ - 1;
  pool.reserve(static_cast<std::size_t>(extra));
  for (int t = 0; t < extra; ++t) {
    try {
      pool.push_back(start_thread_([this] { worker(); }));
    } catch (const std::system_error&) {
      break;  // the system refuses more threads: the workers started (and the caller) do all the work
    }
  }
  worker();
  for (std::thread& t : pool) t.join();
  std::exception_ptr error;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    error = job_error_;
    job_ = nullptr;
    jobs_ = 0;
    next_job_ = 0;
    jobs_done_ = 0;
    job_error_ = nullptr;
  }
  if (error) std::rethrow_exception(error);
}

void JobPool::fanOut(int tasks, const std::function<void(int)>& task) {
  if (tasks <= 0) return;
  if (tasks == 1) {  // nothing to share
    task(0);
    return;
  }
  Batch b;
  b.task = &task;
  b.size = tasks;
  b.error_index = tasks;
  std::unique_lock<std::mutex> lock(mutex_);
  open_.push_back(&b);
  wake_.notify_all();
  while (b.next < b.size) runOneTask(b, lock);
  wake_.wait(lock, [&b] { return b.done == b.size; });
  if (b.error) std::rethrow_exception(b.error);
}

}  // namespace fullarm::core
