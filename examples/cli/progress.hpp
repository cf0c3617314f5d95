#pragma once
// Progress on stderr for long runs: one line redrawn in place (bar, count, elapsed time, ETA),
// only when stderr is a terminal (scripts and CI logs stay clean); finish() clears it before the
// summary is printed.

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace knnocc::cli {

class Progress {
 public:
  Progress(std::string what, std::size_t total)
      : what_(std::move(what)),
        total_(total),
        enabled_(isatty(STDERR_FILENO) == 1 && total > 1),
        start_(std::chrono::steady_clock::now()) {}
  ~Progress() { finish(); }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(std::size_t done) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (done < total_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    constexpr int width = 30;
    const int filled = static_cast<int>(width * done / total_);
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    std::string eta = "--";
    if (done > 0) eta = clock(elapsed / static_cast<double>(done) * double(total_ - done));
    std::fprintf(stderr, "\r\033[K%s [%.*s%*s] %zu/%zu  %s elapsed, ETA %s", what_.c_str(), filled,
                 "##############################", width - filled, "", done, total_,
                 clock(elapsed).c_str(), eta.c_str());
    std::fflush(stderr);
    drawn_ = true;
  }
  /// A new total (work whose size is known only once it starts).
  void retotal(std::size_t total) {
    if (total == total_) return;
    total_ = total;
    enabled_ = enabled_ || (isatty(STDERR_FILENO) == 1 && total > 1 && !finished_);
  }
  /// Clears the line (call before printing the summary).
  void finish() {
    if (drawn_) {
      std::fprintf(stderr, "\r\033[K");
      std::fflush(stderr);
    }
    drawn_ = false;
    enabled_ = false;
    finished_ = true;
  }

 private:
  static std::string clock(double seconds) {
    const long s = static_cast<long>(seconds + 0.5);
    char buf[32];
    if (s >= 3600)
      std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else
      std::snprintf(buf, sizeof buf, "%ld:%02ld", s / 60, s % 60);
    return buf;
  }

  std::string what_;
  std::size_t total_;
  bool enabled_;
  bool drawn_ = false;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_{};
};

}  // namespace knnocc::cli
