// Grid (core/grid.hpp): OctoMap's coordinate-to-key formula, its range, the resolution, point
// types.
#include <doctest/doctest.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <limits>

#include <knnocc/core/grid.hpp>

#include "test_support.hpp"

using knnocc::Grid;
using knnocc::OcKey;
using knnocc::WideKey;

namespace {
struct PclLikePoint {
  float x, y, z, intensity;
};
struct Opaque {
  double v[3];
};
}  // namespace

template <>
struct knnocc::point_traits<Opaque> {
  static constexpr bool is_specialised = true;
  static double x(const Opaque& p) { return p.v[0]; }
  static double y(const Opaque& p) { return p.v[1]; }
  static double z(const Opaque& p) { return p.v[2]; }
};

TEST_CASE("keys.octomap_formula_float_promotion") {
  Grid<OcKey> g(0.1);
  OcKey k;
  // 0.7f * (1 / 0.1) = 6.99999988 in double -> floor 6 (OctoMap's documented example).
  REQUIRE(g.point_to_key(knnocc::Point3f{0.7f, -0.7f, 0.0f}, k));
  CHECK(k[0] == 32768 + 6);
  CHECK(k[1] == 32768 - 7);
  CHECK(k[2] == 32768);
  // The same coordinate as a double is exactly 0.7 -> 7.
  REQUIRE(g.point_to_key(std::array<double, 3>{0.7, 0.0, 0.0}, k));
  CHECK(k[0] == 32768 + 7);
  CHECK(g.index_to_coord(32768) == doctest::Approx(0.05));
  CHECK(g.index_to_coord(32767) == doctest::Approx(-0.05));
}

TEST_CASE("keys.range_checks") {
  Grid<OcKey> g(0.1);
  OcKey k;
  CHECK(g.coord_to_key(-3276.8, 0, 0, k));
  CHECK(k[0] == 0);
  CHECK_FALSE(g.coord_to_key(-3276.81, 0, 0, k));
  CHECK(g.coord_to_key(3276.79, 0, 0, k));
  CHECK(k[0] == 65535);
  CHECK_FALSE(g.coord_to_key(3276.8, 0, 0, k));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CHECK_FALSE(g.coord_to_key(nan, 0, 0, k));
  CHECK_FALSE(g.coord_to_key(0, inf, 0, k));
  CHECK_FALSE(g.coord_to_key(0, 0, -inf, k));
  CHECK_FALSE(g.coord_to_key(1e300, 0, 0, k));

  Grid<WideKey> w(0.1);
  WideKey wk;
  CHECK(w.coord_to_key(50000.0, -50000.0, 104857.5, wk));  // beyond OcKey's ±3.2 km
  CHECK(wk[0] == (1u << 20) + 500000);
  CHECK(w.index_to_coord(wk[0]) == doctest::Approx(50000.05));
  CHECK_FALSE(w.coord_to_key(104857.7, 0, 0, wk));
  CHECK(w.max_coord() == doctest::Approx(104857.6));
}

TEST_CASE("keys.resolution_must_be_positive") {
  CHECK_THROWS_AS(Grid<OcKey>{0.0}, std::invalid_argument);
  CHECK_THROWS_AS(Grid<OcKey>{-0.1}, std::invalid_argument);
  CHECK_THROWS_AS(Grid<OcKey>{std::numeric_limits<double>::quiet_NaN()}, std::invalid_argument);
  CHECK_THROWS_AS(Grid<OcKey>{std::numeric_limits<double>::infinity()}, std::invalid_argument);
  CHECK_THROWS_AS(Grid<OcKey>{1e-320}, std::invalid_argument);  // 1/r overflows
}

TEST_CASE("keys.point_types") {
  Grid<OcKey> g(0.25);
  OcKey a, b, c, d, e;
  REQUIRE(g.point_to_key(PclLikePoint{1.1f, -2.2f, 3.3f, 0.5f}, a));
  REQUIRE(g.point_to_key(Eigen::Vector3f(1.1f, -2.2f, 3.3f), b));
  REQUIRE(g.point_to_key(std::array<float, 3>{1.1f, -2.2f, 3.3f}, c));
  REQUIRE(g.point_to_key(knnocc::Point3f{1.1f, -2.2f, 3.3f}, d));
  REQUIRE(g.point_to_key(Opaque{{1.1, -2.2, 3.3}}, e));
  CHECK(a == b);
  CHECK(a == c);
  CHECK(a == d);
  CHECK(a == e);
  CHECK(a[0] == 32768 + 4);
  CHECK(a[1] == 32768 - 9);
  static_assert(std::is_same_v<knnocc::point_scalar_t<Eigen::Vector3d>, double>);
  static_assert(std::is_same_v<knnocc::point_scalar_t<PclLikePoint>, float>);
  static_assert(knnocc::is_point_v<Opaque>);
  static_assert(!knnocc::is_point_v<int>);
  static_assert(!knnocc::is_point_v<std::array<float, 2>>);
}
