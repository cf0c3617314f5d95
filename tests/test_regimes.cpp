// sim/regimes.hpp: the named outlier regimes and their calibration against the real stereo set.

#include <doctest/doctest.h>

#include <knnocc/sim/regimes.hpp>

using namespace knnocc;

TEST_CASE("regimes: the named regimes exist and differ as documented") {
  const auto r = sim::named_regimes();
  REQUIRE(r.size() == 4);
  sim::Regime x;
  CHECK(sim::find_regime("isolated", x));
  CHECK(x.params.outlier_cluster == 1);
  CHECK(x.params.outlier_repeat == 0);
  CHECK(sim::find_regime("clustered", x));
  CHECK(x.params.outlier_cluster > 1);
  CHECK(sim::find_regime("repeated", x));
  CHECK(x.params.outlier_repeat > 0);
  CHECK_FALSE(sim::find_regime("nope", x));
}

TEST_CASE("regimes: realistic is calibrated near the real set's seen-once fraction (6.6 %)") {
  sim::Regime r;
  REQUIRE(sim::find_regime("realistic", r));
  double mean = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    r.params.seed = seed;
    mean += sim::seen_once_fraction(sim::TreeScene(r.params).keyframes(), 4.0) / 3;
  }
  CHECK(mean > 0.04);
  CHECK(mean < 0.10);
  sim::Regime iso;
  REQUIRE(sim::find_regime("isolated", iso));
  CHECK(sim::seen_once_fraction(sim::TreeScene(iso.params).keyframes(), 4.0) > 0.2);
}
