// RunningNormal: eq 6-12 against a fresh two-pass computation.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <knnocc/stats/welford.hpp>

#include "test_support.hpp"

namespace {
struct Fresh {
  std::size_t n = 0;
  double mean = 0, s = 0;
};
Fresh fresh(const std::vector<double>& v) {
  Fresh f;
  f.n = v.size();
  if (v.empty()) return f;
  for (double x : v) f.mean += x;
  f.mean /= static_cast<double>(v.size());
  for (double x : v) f.s += (x - f.mean) * (x - f.mean);
  return f;
}
bool rel_close(double a, double b, double tol) {
  return std::fabs(a - b) <= tol * std::max({std::fabs(a), std::fabs(b), 1e-300});
}
}  // namespace

TEST_CASE("welford.edge_cases") {
  knnocc::RunningNormal d;
  CHECK(d.count() == 0);
  CHECK(d.sigma() == 0.0);
  CHECK_FALSE(d.erase(1.0));  // erase on empty: refused, nothing changes
  CHECK(d.count() == 0);
  d.add(2.5);
  CHECK(d.mean() == 2.5);
  CHECK(d.sum_squares() == 0.0);
  CHECK(d.sigma() == 0.0);  // N == 1
  d.add(3.5);
  CHECK(d.mean() == doctest::Approx(3.0));
  CHECK(d.sigma() == doctest::Approx(0.5));  // population sigma, eq 12
  CHECK(d.erase(3.5));
  CHECK(d.count() == 1);
  CHECK(d.sum_squares() == 0.0);  // exactly, not a rounding residue
  CHECK(d.mean() == doctest::Approx(2.5));
  CHECK(d.erase(2.5));
  CHECK(d.count() == 0);
  CHECK(d.mean() == 0.0);  // erase down to empty resets exactly
  CHECK(d.sum_squares() == 0.0);
  // Zero variance: identical values.
  for (int i = 0; i < 100; ++i) d.add(0.125);
  CHECK(d.sigma() == 0.0);
  CHECK(d.mean() == 0.125);
}

TEST_CASE("welford.random_add_erase_matches_fresh_computation") {
  knnocc::test::Rng rng(2024);
  // s values of a map cloud: positive, mean ~0.1 m, spread ~0.03 m, a few gross outliers.
  std::normal_distribution<double> s_like(0.1, 0.03);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  knnocc::RunningNormal d;
  std::vector<double> present;
  std::size_t ops = 0;
  while (ops < 100000) {
    const bool erase = !present.empty() && (u(rng) < 0.45 || present.size() > 3000);
    if (erase) {
      const std::size_t i = static_cast<std::size_t>(u(rng) * present.size()) % present.size();
      REQUIRE(d.erase(present[i]));
      present[i] = present.back();
      present.pop_back();
    } else {
      const double x = u(rng) < 0.01 ? 5.0 + u(rng) : std::fabs(s_like(rng));
      d.add(x);
      present.push_back(x);
    }
    ++ops;
    if (ops % 10000 == 0 || present.size() < 3) {
      const Fresh f = fresh(present);
      REQUIRE(d.count() == f.n);
      CHECK(rel_close(d.mean(), f.mean, 1e-9));
      CHECK(rel_close(d.sum_squares(), f.s, 1e-9));
    }
  }
  const Fresh f = fresh(present);
  CHECK(d.count() == f.n);
  CHECK(rel_close(d.mean(), f.mean, 1e-9));
  CHECK(rel_close(d.sigma(), std::sqrt(f.s / f.n), 1e-9));
  // recompute() gives the two-pass state itself.
  knnocc::RunningNormal r;
  r.recompute(present);
  CHECK(r.count() == f.n);
  CHECK(r.mean() == f.mean);
  CHECK(r.sum_squares() == f.s);
}
