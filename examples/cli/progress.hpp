#pragma once
// Progress on stderr for long runs: a one-line bar redrawn in place, only when stderr is a
// terminal (scripts and CI logs stay clean).

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace knnocc::cli {

class Progress {
 public:
  Progress(std::string what, std::size_t total)
      : what_(std::move(what)), total_(total), enabled_(isatty(STDERR_FILENO) == 1 && total > 1) {}
  ~Progress() { finish(); }

  void update(std::size_t done) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (done < total_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    constexpr int width = 30;
    const int filled = static_cast<int>(width * done / total_);
    std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu", what_.c_str(), filled,
                 "##############################", width - filled, "", done, total_);
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\r\033[K");
    drawn_ = false;
  }

 private:
  std::string what_;
  std::size_t total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace knnocc::cli
