#pragma once
// The k-NN oracle: the check that a tracker agrees exactly with the brute-force truth
// (knn_truth.hpp).

#include <doctest/doctest.h>

#include <cmath>

#include "knn_truth.hpp"

namespace knnocc::test {

template <class Tracker>
void expect_matches(const Tracker& tr, const Cloud& cloud) {
  const Truth t = brute_force(cloud, tr.params().k, tr.params().s_limit);
  REQUIRE(tr.size() == cloud.size());
  std::size_t wrong_sets = 0, wrong_s = 0;
  for (const auto& [id, p] : cloud) {
    REQUIRE(tr.contains(id));
    if (tr.neighbours(id) != t.knn.at(id)) ++wrong_sets;
    const double a = tr.s(id), b = t.s.at(id);
    if (!(a == b || (std::isnan(a) && std::isnan(b)))) ++wrong_s;
  }
  CHECK(wrong_sets == 0);
  CHECK(wrong_s == 0);
  CHECK(tr.N() == t.n);
  CHECK(rel_close(tr.mu(), t.mean, 1e-9));
  CHECK(rel_close(tr.sigma(), t.sigma, 1e-9));
}

}  // namespace knnocc::test
