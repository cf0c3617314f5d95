// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How ScanInserter shares a pass between its threads: a Team runs one job on every thread (the
// calling thread is thread 0; the others come from a ThreadPool made on the first multithreaded
// pass), and a WorkQueue hands out the items of one pass (chunks of points, chunks of rays, groups
// of brick rows or of bricks) to whichever thread asks next. Each pass makes its own queue.

#include <atomic>
#include <cstddef>
#include <memory>

#include "../../core/config.hpp"
#include "thread_pool.hpp"

namespace knnocc::detail {

/// The items [0, size) of one pass, each taken by exactly one thread.
class WorkQueue {
 public:
  explicit WorkQueue(std::size_t size) : size_(size) {}
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  std::size_t size() const { return size_; }
  /// The next item not taken yet; false when every item is taken.
  bool take(std::size_t& item) {
    item = next_.fetch_add(1, std::memory_order_relaxed);
    return item < size_;
  }

 private:
  std::atomic<std::size_t> next_{0};
  std::size_t size_;
};

/// A fixed number of threads that run each job together: run(job) calls job(t) once for every
/// thread t in [0, size()) and returns when all calls have returned.
class Team {
 public:
  explicit Team(unsigned size = 1) : size_(size) {}
  Team(Team&&) noexcept = default;
  Team& operator=(Team&&) noexcept = default;

  unsigned size() const { return size_; }
  /// A new size for the following runs (the worker threads are remade on the next run).
  void resize(unsigned size) {
    if (size == size_) return;
    size_ = size;
    pool_.reset();
  }
  template <class Job>
  void run(Job& job) {
    if (size_ == 1) {
      job(0u);
      return;
    }
    if (!pool_) pool_ = std::make_unique<ThreadPool>(size_);
    pool_->run(job);
  }
  /// run(), on the first `threads` threads only (the others do nothing): one thread where waking
  /// the others would cost more than the work.
  template <class Job>
  void run_on(unsigned threads, Job& job) {
    if (threads <= 1) {
      job(0u);
      return;
    }
    auto some = [&](unsigned t) {
      if (t < threads) job(t);
    };
    run(some);
  }

 private:
  unsigned size_;
  std::unique_ptr<ThreadPool> pool_;  // made on the first run with more than one thread
};

}  // namespace knnocc::detail
