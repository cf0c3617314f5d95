#pragma once
// ThreadPool: a fixed set of threads running one job at a time (ScanInserter's --threads).
//
// run(job) calls job(w) once for every worker w in [0, size()), worker 0 being the calling thread,
// and returns when every call has returned. The workers sleep on a condition variable between
// jobs; a run allocates nothing. An exception thrown by a job is rethrown by run() once every
// worker is done with the job.

#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "../core/config.hpp"

namespace knnocc::detail {

class ThreadPool {
 public:
  explicit ThreadPool(unsigned size) : size_(size < 1 ? 1 : size) {
    threads_.reserve(size_ - 1);
    for (unsigned w = 1; w < size_; ++w) threads_.emplace_back([this, w] { work(w); });
  }
  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
  }
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  unsigned size() const { return size_; }

  template <class Job>
  void run(Job& job) {
    if (size_ == 1) {
      job(0u);
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &job;
      call_ = [](void* j, unsigned w) { (*static_cast<Job*>(j))(w); };
      pending_ = size_ - 1;
      ++generation_;
    }
    wake_.notify_all();
    run_guarded(0);
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return pending_ == 0; });
    job_ = nullptr;
#if KNNOCC_HAS_EXCEPTIONS
    if (error_) {
      std::exception_ptr e = error_;
      error_ = nullptr;
      std::rethrow_exception(e);
    }
#endif
  }

 private:
  void run_guarded(unsigned w) {
#if KNNOCC_HAS_EXCEPTIONS
    try {
      call_(job_, w);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
    }
#else
    call_(job_, w);
#endif
  }

  void work(unsigned w) {
    std::uint64_t seen = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      run_guarded(w);  // job_ and call_ stay fixed until every worker has reported back
      std::lock_guard<std::mutex> lock(mutex_);
      if (--pending_ == 0) done_.notify_one();
    }
  }

  unsigned size_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  void* job_ = nullptr;
  void (*call_)(void*, unsigned) = nullptr;
  unsigned pending_ = 0;
  std::uint64_t generation_ = 0;
  bool stop_ = false;
#if KNNOCC_HAS_EXCEPTIONS
  std::exception_ptr error_;
#endif
};

}  // namespace knnocc::detail
