// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RunningNormal: the normal distribution of the s values (paper eq 5), kept up to date with
// Welford's corrected sums of squares when values are added (eq 6-8) AND erased (eq 9-11);
// sigma = sqrt(S / N) (eq 12).
//
// Defined edge cases:
//   N == 0: mean() == 0, S() == 0, sigma() == 0 (no information; erase() on empty is ignored
//           and reported by its return value).
//   N == 1: S() == 0 exactly (one value has no spread), sigma() == 0.
//   Erasing down to N == 0 resets mean and S to exactly 0, so no rounding residue survives.
//   S never goes below 0 (rounding in eq 10 is clamped).
// Erasing a value that was never added corrupts the state; callers (the tracker) only erase
// values they added. Long add/erase runs accumulate rounding; KnnTracker bounds it with an exact
// refresh (see knn/tracker.hpp).
//
// Thread safety: a plain value; const functions may run concurrently, writes need exclusivity.

#include <cmath>
#include <cstddef>

namespace knnocc {

class RunningNormal {
 public:
  std::size_t count() const { return n_; }
  double mean() const { return mean_; }
  /// S: sum of squared deviations from the mean.
  double sum_squares() const { return s_; }
  /// Population standard deviation sqrt(S / N) (eq 12); 0 when N == 0.
  double sigma() const { return n_ ? std::sqrt(s_ / static_cast<double>(n_)) : 0.0; }
  double variance() const { return n_ ? s_ / static_cast<double>(n_) : 0.0; }

  /// Eq 6-8.
  void add(double x) {
    ++n_;
    const double n = static_cast<double>(n_);
    s_ += (n - 1.0) / n * (x - mean_) * (x - mean_);  // eq 7, with the old mean
    mean_ = (n - 1.0) / n * mean_ + x / n;            // eq 8
  }

  /// Eq 9-11. Returns false (and changes nothing) when the distribution is empty.
  bool erase(double x) {
    if (n_ == 0) return false;
    if (n_ == 1) {
      reset();
      return true;
    }
    const double n = static_cast<double>(n_);
    mean_ = n / (n - 1.0) * mean_ - x / (n - 1.0);    // eq 9
    s_ -= (n - 1.0) / n * (x - mean_) * (x - mean_);  // eq 10, with the new mean
    --n_;                                             // eq 11
    if (n_ == 1 || s_ < 0.0) s_ = 0.0;
    return true;
  }

  void reset() {
    n_ = 0;
    mean_ = 0.0;
    s_ = 0.0;
  }

  /// Replaces the state by an exact two-pass computation over `values` (a range of double).
  template <class Range>
  void recompute(const Range& values) {
    reset();
    double sum = 0.0;
    for (const double v : values) {
      sum += v;
      ++n_;
    }
    if (n_ == 0) return;
    mean_ = sum / static_cast<double>(n_);
    for (const double v : values) s_ += (v - mean_) * (v - mean_);
  }

 private:
  std::size_t n_ = 0;
  double mean_ = 0.0;
  double s_ = 0.0;
};

}  // namespace knnocc
