#pragma once
// Guard: the library's thread-safety contract (README "Thread safety") enforced per object. One
// writer, or any number of readers while no writer runs: a call that would break it is refused
// with std::runtime_error (RuntimeError in Python) before it starts, never left to race. The
// module takes a guard while it still holds the GIL, then releases the GIL for the work.

#include <atomic>
#include <stdexcept>
#include <string>

namespace knnocc::python {

class Guard {
 public:
  /// Held for the length of one call; releases on destruction.
  class Scope {
   public:
    Scope(Guard* g, bool writer) : g_(g), writer_(writer) {}
    Scope(Scope&& o) noexcept : g_(o.g_), writer_(o.writer_) { o.g_ = nullptr; }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
    Scope& operator=(Scope&&) = delete;
    ~Scope() {
      if (!g_) return;
      if (writer_) {
        g_->writer_.store(nullptr);
        g_->state_.store(0);
      } else {
        g_->state_.fetch_sub(1);
      }
    }

   private:
    Guard* g_;
    bool writer_;
  };

  /// `what` (e.g. "Mapper.insert_keyframe") changes the object: nobody else may be in it.
  Scope write(const char* what) {
    int idle = 0;
    if (!state_.compare_exchange_strong(idle, -1)) refuse(what, idle);
    writer_.store(what);
    return Scope(this, true);
  }

  /// `what` only reads: refused while a writer runs, shared with other readers.
  Scope read(const char* what) {
    int n = state_.load();
    do {
      if (n < 0) refuse(what, n);
    } while (!state_.compare_exchange_weak(n, n + 1));
    return Scope(this, false);
  }

 private:
  [[noreturn]] void refuse(const char* what, int state) const {
    const char* writer = writer_.load();
    const std::string busy = state < 0 ? std::string("another thread is running ") +
                                             (writer ? writer : "a change") + " on it"
                                       : std::string("another thread is reading it");
    throw std::runtime_error(std::string(what) + ": refused, " + busy +
                             " (one writer per object, and no reads while it writes)");
  }

  std::atomic<int> state_{0};  // -1: a writer; n > 0: n readers
  std::atomic<const char*> writer_{nullptr};
};

}  // namespace knnocc::python
