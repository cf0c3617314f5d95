// A brick's value updates (map/detail/brick_values.hpp): eight voxels at a time or one by one,
// the same floats.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include <knnocc/map/occupancy_map.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::WideKey;

TEST_CASE("map.brick_value_updates_match_voxel_by_voxel") {
  // update_values_avx2 (eight voxels at a time) against update_values_scalar, bit for bit: values
  // at, beside and beyond the clamping bounds, signed zeros, unknown voxels, masks from empty to
  // full, deltas of both signs and zero, bounds on either side of zero and at zero.
#if KNNOCC_AVX2_LANES
  if (!knnocc::detail::cpu_has_avx2()) {
    knnocc::test::skip("update_values_avx2: not tested, this CPU has no AVX2");
    return;
  }
  knnocc::test::Rng rng(61);
  const std::vector<std::pair<float, float>> bounds = {
      {-2.00002789f, 3.51103067f}, {-1.f, 0.f}, {0.f, 1.f}, {-0.f, 2.f}};
  const std::vector<float> deltas = {0.85f, -0.4f, 0.f, -0.f, 5.f, -5.f, 1e-8f};
  std::uniform_real_distribution<float> u(-4.f, 4.f);
  std::uniform_int_distribution<int> pick(0, 10);
  std::size_t updated = 0;
  for (const auto& bound : bounds)
    for (const float delta : deltas) {
      const float lo = bound.first, hi = bound.second;  // no structured binding: CAPTURE below
      const knnocc::detail::ValueUpdate up{delta, std::min(std::max(0.f + delta, lo), hi), lo, hi};
      for (int round = 0; round < 200; ++round) {
        std::vector<float> a(512);
        for (float& v : a) {
          switch (pick(rng)) {
            case 0:
              v = lo;
              break;
            case 1:
              v = hi;
              break;
            case 2:
              v = std::nextafter(lo, 0.f);
              break;
            case 3:
              v = std::nextafter(hi, 0.f);
              break;
            case 4:
              v = pick(rng) < 5 ? 0.f : -0.f;
              break;
            case 5:
              v = hi - delta;
              break;
            case 6:  // v + delta is exactly zero: signed zeros against a bound at zero
              v = -delta;
              break;
            default:
              v = u(rng);
          }
        }
        std::uint64_t mask[8], known[8];
        for (int j = 0; j < 8; ++j) {
          mask[j] = rng();
          known[j] = rng();
          if (round % 4 == 0) mask[j] &= rng();  // sparser masks
          if (round % 5 == 0) mask[j] = j % 2 ? ~std::uint64_t{0} : 0;
          if (round % 7 == 0) known[j] = ~std::uint64_t{0};
        }
        std::vector<float> b = a;
        knnocc::detail::update_values_scalar(a.data(), mask, known, 8, up);
        knnocc::detail::update_values_avx2(b.data(), mask, known, 8, up);
        CAPTURE(lo);
        CAPTURE(delta);
        CAPTURE(round);
        REQUIRE(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
        for (int j = 0; j < 8; ++j)
          updated += static_cast<std::size_t>(__builtin_popcountll(mask[j]));
      }
    }
  MESSAGE(updated << " voxel updates compared");
#else
  knnocc::test::skip("update_values_avx2: not built here (no x86-64 AVX2 code path)");
#endif
}
