#pragma once
// The k-NN truth by definition (brute force): s_p, k-NN sets and the distribution of a cloud.
// No test framework here, so the fuzzers use it too (tests/fuzz).

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <knnocc/knn/point_index.hpp>

namespace knnocc::test {

using Cloud = std::map<std::uint64_t, knnocc::Point3d>;

struct Truth {
  std::map<std::uint64_t, std::vector<std::uint64_t>> knn;
  std::map<std::uint64_t, double> s;
  std::size_t n = 0;
  double mean = 0, sigma = 0;
};

// The definition itself: sort every other point by (dist2, id), take k, average the distances.
inline Truth brute_force(const Cloud& cloud, std::size_t k, double s_limit) {
  Truth t;
  std::vector<std::pair<std::uint64_t, knnocc::Point3d>> pts(cloud.begin(), cloud.end());
  std::vector<knnocc::Neighbor> all;
  std::vector<double> valid;
  for (const auto& [id, p] : pts) {
    all.clear();
    for (const auto& [jd, q] : pts)
      if (jd != id) all.push_back({0, jd, knnocc::dist2(q, p)});
    const std::size_t m = std::min(k, all.size());
    std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(m), all.end(),
                      [](const knnocc::Neighbor& a, const knnocc::Neighbor& b) {
                        return knnocc::closer(a.d2, a.id, b.d2, b.id);
                      });
    auto& ids = t.knn[id];
    double sum = 0;
    for (std::size_t j = 0; j < m; ++j) {
      ids.push_back(all[j].id);
      sum += std::sqrt(all[j].d2);
    }
    const double s = m == k ? sum / static_cast<double>(k) : std::nan("");
    t.s[id] = s;
    if (!std::isnan(s) && s < s_limit) valid.push_back(s);
  }
  t.n = valid.size();
  if (t.n) {
    for (double v : valid) t.mean += v;
    t.mean /= static_cast<double>(t.n);
    double ss = 0;
    for (double v : valid) ss += (v - t.mean) * (v - t.mean);
    t.sigma = std::sqrt(ss / static_cast<double>(t.n));
  }
  return t;
}

inline bool rel_close(double a, double b, double tol) {
  return std::fabs(a - b) <= tol * std::max(std::max(std::fabs(a), std::fabs(b)), 1e-12);
}

}  // namespace knnocc::test
