// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ThreadPool: a fixed set of threads running one job at a time (ScanInserter's --threads).
//
// run(job) calls job(w) once for every worker w in [0, size()), worker 0 being the calling thread,
// and returns when every call has returned. A run allocates nothing. An exception thrown by a job
// is rethrown by run() once every worker is done with the job.
//
// One scan is a few runs in quick succession, and waking a thread that sleeps on a condition
// variable costs more than a short run (bench/NOTES.md has the figures). So between runs the
// workers first spin (for kSpin) on the run counter, and only then sleep; run() likewise spins a
// while for the workers to finish before it sleeps. Idle workers stop using the CPU after kSpin. A
// pool of more threads than the machine has hardware threads never spins: a spinning worker would
// take a core from a thread with work.
//
// A worker thread that cannot be started (the system's thread or memory limit) is an error, never
// a hang: the constructor stops and joins the workers it did start and throws std::system_error
// ("cannot start thread W of N: ..."); without exceptions it aborts, as std::thread does.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "../../core/config.hpp"

namespace knnocc::detail {

/// A hint to the CPU inside a spin loop.
inline void spin_pause() {
#if (defined(__GNUC__) || defined(__clang__)) && (defined(__x86_64__) || defined(__i386__))
  __builtin_ia32_pause();
#elif (defined(__GNUC__) || defined(__clang__)) && defined(__aarch64__)
  asm volatile("yield");
#else
  std::this_thread::yield();
#endif
}

class ThreadPool {
 public:
  /// How long a worker spins for the next run, and run() for the workers, before sleeping.
  static constexpr std::chrono::microseconds kSpin{200};

  /// Starts worker w's thread running `body` (std::thread by default; tests make it fail).
  using StartThread = std::thread (*)(unsigned w, std::function<void()> body);
  static std::thread start_thread(unsigned, std::function<void()> body) {
    return std::thread(std::move(body));
  }

  explicit ThreadPool(unsigned size, StartThread start = start_thread)
      : size_(size < 1 ? 1 : size), spin_(size_ <= std::thread::hardware_concurrency()) {
    threads_.reserve(size_ - 1);
#if KNNOCC_HAS_EXCEPTIONS
    try {
      for (unsigned w = 1; w < size_; ++w) threads_.push_back(start(w, [this, w] { work(w); }));
    } catch (const std::system_error& e) {
      const std::size_t started = threads_.size();  // workers 1..started run
      stop();
      throw std::system_error(e.code(), "cannot start thread " + std::to_string(started + 1) +
                                            " of " + std::to_string(size_));
    } catch (...) {
      stop();
      throw;
    }
#else
    for (unsigned w = 1; w < size_; ++w) threads_.push_back(start(w, [this, w] { work(w); }));
#endif
  }
  ~ThreadPool() { stop(); }
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  unsigned size() const { return size_; }

  template <class Job>
  void run(Job& job) {
    if (size_ == 1) {
      job(0u);
      return;
    }
    job_ = &job;
    call_ = [](void* j, unsigned w) { (*static_cast<Job*>(j))(w); };
    pending_.store(size_ - 1, std::memory_order_relaxed);
    {
      // Under the mutex, so that a worker deciding to sleep sees either the new run or the wake.
      std::lock_guard<std::mutex> lock(mutex_);
      generation_.fetch_add(1, std::memory_order_release);  // publishes job_ and call_
    }
    wake_.notify_all();
    run_guarded(0);
    if (!spin_until([this] { return pending_.load(std::memory_order_acquire) == 0; }, spin_)) {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
    }
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
  // Spins until done() or kSpin has passed (not at all unless `spin`); returns done().
  template <class Done>
  static bool spin_until(Done done, bool spin) {
    if (!spin) return done();
    const auto deadline = std::chrono::steady_clock::now() + kSpin;
    for (;;) {
      for (int i = 0; i < 64; ++i) {
        if (done()) return true;
        spin_pause();
      }
      if (std::chrono::steady_clock::now() > deadline) return done();
    }
  }

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

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_.store(true, std::memory_order_release);
    }
    wake_.notify_all();
    for (std::thread& t : threads_) t.join();
    threads_.clear();
  }

  void work(unsigned w) {
    std::uint64_t seen = 0;
    auto next_run = [&] {
      return stop_.load(std::memory_order_acquire) ||
             generation_.load(std::memory_order_acquire) != seen;
    };
    for (;;) {
      if (!spin_until(next_run, spin_)) {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, next_run);
      }
      if (stop_.load(std::memory_order_acquire)) return;
      seen = generation_.load(std::memory_order_acquire);
      run_guarded(w);  // job_ and call_ stay fixed until every worker has reported back
      if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
        // Under the mutex: run() either has not checked pending_ yet or is waiting for this.
        std::lock_guard<std::mutex> lock(mutex_);
        done_.notify_one();
      }
    }
  }

  unsigned size_;
  bool spin_;  // no more threads than hardware threads
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  void* job_ = nullptr;
  void (*call_)(void*, unsigned) = nullptr;
  std::atomic<unsigned> pending_{0};
  std::atomic<std::uint64_t> generation_{0};
  std::atomic<bool> stop_{false};
#if KNNOCC_HAS_EXCEPTIONS
  std::exception_ptr error_;
#endif
};

}  // namespace knnocc::detail
