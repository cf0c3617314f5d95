// finite_bounds (insertion/detail/point_bounds.hpp) against a loop over the points.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <set>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;
using knnocc::WideKey;

TEST_CASE_TEMPLATE("insert.eight_point_keys_match_key_rounding", Key, knnocc::OcKey,
                   knnocc::WideKey) {
  // point_keys8 (the chunked collect's keys, eight points at a time) against KeyRounding, point
  // by point: coordinates of every size, on voxel borders and a few float steps beside them,
  // at the ends of the key range and beyond it, NaN and Inf. It must give the same keys when all
  // eight are in range and report false exactly when one of them is not.
#if KNNOCC_AVX2_LANES
  if (!knnocc::detail::cpu_has_avx2()) {
    knnocc::test::skip("point_keys8: not tested, this CPU has no AVX2");
    return;
  }
  knnocc::test::Rng rng(47);
  for (const double res : {0.05, 0.1, 0.37}) {
    CAPTURE(res);
    const knnocc::Grid<Key> grid(res);
    const knnocc::detail::KeyRounding<Key> rounding(grid);
    const auto edge = static_cast<float>(static_cast<double>(Key::center) * res);
    std::uniform_real_distribution<float> small(-3.f, 3.f), any(-edge, edge);
    std::uniform_int_distribution<int> kind(0, 15), cell(-1000, 1000), ulps(-3, 3);
    const auto coordinate = [&]() -> float {
      switch (kind(rng)) {
        case 0:
          return std::numeric_limits<float>::quiet_NaN();
        case 1:
          return kind(rng) < 8 ? std::numeric_limits<float>::infinity()
                               : -std::numeric_limits<float>::infinity();
        case 2:  // at the ends of the key range
          return std::nextafter(kind(rng) < 8 ? edge : -edge, ulps(rng) < 0 ? 0.f : INFINITY);
        case 3:
        case 4:
        case 5: {  // on or beside a voxel border
          float v = static_cast<float>(cell(rng) * res);
          for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1)
            v = std::nextafter(v, k > 0 ? INFINITY : -INFINITY);
          return v;
        }
        case 6:
          return any(rng);
        default:
          return small(rng);
      }
    };
    std::size_t in_range = 0, blocks = 0;
    for (int b = 0; b < 20000; ++b) {
      Point3f p[8];
      const bool clean = b % 4 != 0;  // most blocks without NaN, Inf or the range ends
      for (auto& q : p) {
        q = {coordinate(), coordinate(), coordinate()};
        if (clean)
          for (float* c : {&q.x, &q.y, &q.z})
            if (!(std::fabs(*c) < 0.5f * edge)) *c = small(rng);
      }
      std::int32_t key[3][8];
      const bool ok = knnocc::detail::point_keys8<Key>(p, rounding.inverse_resolution(), key);
      bool want = true;
      std::int64_t k[8][3];
      for (int j = 0; j < 8; ++j) want = rounding.point_to_key(p[j], k[j]) && want;
      CAPTURE(b);
      REQUIRE(ok == want);
      ++blocks;
      if (!ok) continue;
      ++in_range;
      for (int j = 0; j < 8; ++j)
        for (int a = 0; a < 3; ++a) CHECK(key[a][j] == k[j][a]);
    }
    CHECK(in_range > blocks / 2);
    CHECK(in_range < blocks);
  }
#else
  knnocc::test::skip("point_keys8: not built here (no x86-64 AVX2 code path)");
#endif
}

TEST_CASE("insert.finite_bounds_match_a_point_loop") {
  // The vectorised bounds of a large scan's points against a plain loop: every length from 0 to
  // 40 (whole blocks of eight and remainders), with and without a NaN or Inf at each position.
  knnocc::test::Rng rng(43);
  std::uniform_real_distribution<float> u(-50.f, 50.f);
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity(),
                       -std::numeric_limits<float>::infinity()};
  for (std::size_t n = 0; n <= 40; ++n) {
    std::vector<Point3f> pts(n);
    for (auto& p : pts) p = {u(rng), u(rng), u(rng)};
    const float start_lo[3] = {1.f, 2.f, 3.f}, start_hi[3] = {4.f, 5.f, 6.f};
    float lo[3], hi[3], want_lo[3], want_hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = want_lo[a] = start_lo[a];
      hi[a] = want_hi[a] = start_hi[a];
    }
    for (const auto& p : pts)
      for (int a = 0; a < 3; ++a) {
        const float c = a == 0 ? p.x : a == 1 ? p.y : p.z;
        want_lo[a] = std::min(want_lo[a], c);
        want_hi[a] = std::max(want_hi[a], c);
      }
    CAPTURE(n);
    REQUIRE(knnocc::detail::finite_bounds(pts.data(), n, lo, hi));
    for (int a = 0; a < 3; ++a) {
      CHECK(lo[a] == want_lo[a]);
      CHECK(hi[a] == want_hi[a]);
    }
    for (std::size_t i = 0; i < n; ++i) {  // one bad coordinate anywhere: false, bounds untouched
      auto spoiled = pts;
      const int axis = static_cast<int>(i % 3);
      (axis == 0 ? spoiled[i].x : axis == 1 ? spoiled[i].y : spoiled[i].z) = bad[i % 3];
      float l[3] = {start_lo[0], start_lo[1], start_lo[2]};
      float h[3] = {start_hi[0], start_hi[1], start_hi[2]};
      CAPTURE(i);
      CHECK_FALSE(knnocc::detail::finite_bounds(spoiled.data(), n, l, h));
      for (int a = 0; a < 3; ++a) {
        CHECK(l[a] == start_lo[a]);
        CHECK(h[a] == start_hi[a]);
      }
    }
  }
}
