// KnnModel (eq 13-15) against an independent evaluation of the formula: the normal CDF by
// numerical integration of the density (eq 5), not erfc.

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include <knnocc/sensor/knn_model.hpp>

using namespace knnocc;

namespace {

// Integral of the N(mu, sigma) density from mu - 12 sigma to x (composite Simpson).
double cdf_by_integration(double x, double mu, double sigma) {
  const double a = mu - 12 * sigma;
  if (x <= a) return 0.0;
  const int n = 20000;
  const double h = (x - a) / n;
  auto f = [&](double s) {
    return std::exp(-(s - mu) * (s - mu) / (2 * sigma * sigma)) /
           std::sqrt(2 * M_PI * sigma * sigma);
  };
  double sum = f(a) + f(x);
  for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4 : 2);
  return sum * h / 3;
}

RunningNormal distribution_of(std::initializer_list<double> values) {
  RunningNormal d;
  for (double v : values) d.add(v);
  return d;
}

}  // namespace

TEST_CASE("knn_model: eq 13 and the eq 14 gate match the formula evaluated independently") {
  const RunningNormal dist = distribution_of({0.10, 0.12, 0.15, 0.11, 0.30, 0.09, 0.14, 0.13});
  const double mu = dist.mean(), sigma = dist.sigma();
  REQUIRE(sigma > 0);
  for (const double w : {-1.0, 0.0, 0.5, 1.0, 2.0}) {
    KnnModelParams p;
    p.w = w;
    p.p_upper = 0.85;
    p.p_w = 0.6;
    const KnnModel model(p);
    const double denom = cdf_by_integration(w * sigma + mu, mu, sigma);
    double previous = 1.0;
    for (double s = 0.0; s < 0.6; s += 0.01) {
      const double expect =
          std::max(KnnModel::kMinProb,
                   p.p_upper - cdf_by_integration(s, mu, sigma) / denom * (p.p_upper - p.p_w));
      const double got = model.probability(s, dist);
      CHECK(got == doctest::Approx(expect).epsilon(1e-7));
      CHECK(got <= previous);  // more isolated points are less probable
      previous = got;
      const EndpointRating r = model.rate(s, dist);
      CHECK(r.logodds == doctest::Approx(std::log(got / (1 - got))).epsilon(1e-6));
      // Eq 14: a free ray only below the reliability threshold mu + w sigma.
      const double threshold = mu + w * sigma;
      if (std::fabs(s - threshold) > 1e-9) CHECK(r.casts_ray == (s < threshold));
    }
    // Prob(mu + w sigma) = P_w: the parameters' meaning.
    CHECK(model.probability(mu + w * sigma, dist) == doctest::Approx(p.p_w).epsilon(1e-12));
  }
}

TEST_CASE("knn_model: defined edge cases (N = 0, sigma = 0, NaN s, the probability floor)") {
  KnnModelParams p;
  p.w = 1.0;
  p.p_upper = 0.8;
  p.p_w = 0.6;
  const KnnModel model(p);
  const double phi_w = cdf_by_integration(1.0, 0.0, 1.0);
  const double at_infinity = 0.8 - 0.2 / phi_w;

  SUBCASE("N == 0: every endpoint gets exactly P_w and casts no ray") {
    const RunningNormal empty;
    for (double s : {0.0, 0.1, 5.0, std::nan("")}) {
      CHECK(model.probability(s, empty) == 0.6);
      CHECK_FALSE(model.rate(s, empty).casts_ray);
    }
  }
  SUBCASE("sigma == 0 (one value, or all equal): the step at mu") {
    for (const RunningNormal& d : {distribution_of({0.2}), distribution_of({0.2, 0.2, 0.2})}) {
      REQUIRE(d.sigma() == 0.0);
      CHECK(model.probability(0.1, d) == doctest::Approx(0.8));
      CHECK(model.rate(0.1, d).casts_ray);
      CHECK(model.probability(0.2, d) == doctest::Approx(0.8 - 0.5 / phi_w * 0.2).epsilon(1e-9));
      CHECK(model.rate(0.2, d).casts_ray);  // eq 14 literally: Prob = 0.681 > P_w
      CHECK(model.probability(0.3, d) == doctest::Approx(at_infinity).epsilon(1e-9));
      CHECK_FALSE(model.rate(0.3, d).casts_ray);
    }
  }
  SUBCASE("equal values that Welford leaves a few ulps apart count as sigma == 0") {
    RunningNormal d;
    for (int i = 0; i < 20; ++i) d.add(0.1);  // mean 0.1 + ulps, sigma ~1e-17, not exactly 0
    CHECK(d.sigma() < 1e-15);
    CHECK(model.probability(0.1, d) == doctest::Approx(0.8 - 0.5 / phi_w * 0.2).epsilon(1e-9));
    CHECK(model.probability(0.1 - 1e-6, d) == doctest::Approx(0.8));
    CHECK(model.probability(0.1 + 1e-6, d) == doctest::Approx(at_infinity).epsilon(1e-9));
  }
  SUBCASE("s NaN (fewer than k neighbours): the limit s -> +inf") {
    const RunningNormal d = distribution_of({0.1, 0.2, 0.3});
    CHECK(model.probability(std::nan(""), d) == doctest::Approx(at_infinity).epsilon(1e-9));
    CHECK_FALSE(model.rate(std::nan(""), d).casts_ray);
  }
  SUBCASE("a small w drives eq 13 below 0 for isolated points: floored, logit finite") {
    KnnModelParams q = p;
    q.w = -2.5;
    const KnnModel strict(q);
    const RunningNormal d = distribution_of({0.1, 0.2, 0.3});
    CHECK(strict.probability(1.0, d) == KnnModel::kMinProb);
    CHECK(std::isfinite(strict.rate(1.0, d).logodds));
    CHECK(strict.rate(1.0, d).logodds < 0);
  }
}

TEST_CASE("knn_model: invalid parameters are rejected with a message naming the parameter") {
  auto rejects = [](auto change, const char* word) {
    KnnModelParams p;
    change(p);
    try {
      KnnModel m(p);
      FAIL("accepted");
    } catch (const std::invalid_argument& e) {
      CHECK(std::string(e.what()).find(word) != std::string::npos);
    }
  };
  rejects([](KnnModelParams& p) { p.k = 0; }, "k must");
  rejects([](KnnModelParams& p) { p.p_w = 0.5; }, "P_w");
  rejects([](KnnModelParams& p) { p.p_w = 1.0; }, "P_w");
  rejects([](KnnModelParams& p) { p.p_upper = 0.6; }, "P_u");  // not above P_w
  rejects([](KnnModelParams& p) { p.p_upper = 1.0; }, "P_u");
  rejects([](KnnModelParams& p) { p.w = std::nan(""); }, "w must");
  rejects([](KnnModelParams& p) { p.w = 100; }, "w must");
  rejects([](KnnModelParams& p) { p.s_limit = 0; }, "s_limit");
  rejects([](KnnModelParams& p) { p.p_free = 0.5; }, "free");
  CHECK_NOTHROW(KnnModel(KnnModelParams{}));
}
