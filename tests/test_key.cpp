// Keys (core/key.hpp): packing and coarse depths.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>

#include <knnocc/core/grid.hpp>

#include "test_support.hpp"

using knnocc::Grid;
using knnocc::OcKey;
using knnocc::WideKey;

TEST_CASE("keys.pack_roundtrip_and_order") {
  knnocc::test::Rng rng(7);
  std::uniform_int_distribution<std::uint32_t> d16(0, 65535), d21(0, (1u << 21) - 1);
  for (int i = 0; i < 1000; ++i) {
    const OcKey a(static_cast<std::uint16_t>(d16(rng)), static_cast<std::uint16_t>(d16(rng)),
                  static_cast<std::uint16_t>(d16(rng)));
    const OcKey b(static_cast<std::uint16_t>(d16(rng)), static_cast<std::uint16_t>(d16(rng)),
                  static_cast<std::uint16_t>(d16(rng)));
    CHECK(OcKey::unpack(a.pack()) == a);
    CHECK((a < b) == (a.pack() < b.pack()));  // packing keeps the x, y, z order
    const WideKey w(d21(rng), d21(rng), d21(rng));
    CHECK(WideKey::unpack(w.pack()) == w);
  }
}

TEST_CASE("keys.shifted_key_stays_in_the_key_range") {
  OcKey n;
  REQUIRE(knnocc::shifted_key(OcKey(10, 20, 30), -1, 0, 1, n));
  CHECK(n == OcKey(9, 20, 31));
  const std::uint16_t top = static_cast<std::uint16_t>(OcKey::extent - 1);
  CHECK(knnocc::shifted_key(OcKey(0, top, 5), 0, 0, -1, n));
  CHECK(n == OcKey(0, top, 4));
  CHECK_FALSE(knnocc::shifted_key(OcKey(0, 5, 5), -1, 0, 0, n));   // below index 0
  CHECK_FALSE(knnocc::shifted_key(OcKey(5, top, 5), 0, 1, 0, n));  // past the last index
  WideKey w;
  CHECK(knnocc::shifted_key(WideKey(1u << 20, 0, 7), 1, 1, -7, w));  // wider than 16 bits
  CHECK(w == WideKey((1u << 20) + 1, 1, 0));
}

TEST_CASE("keys.coarse_depth") {
  Grid<OcKey> g(0.1);
  const OcKey k(32768 + 5, 32768 - 3, 32768);
  // Depth 15: node of 2 leaves; low bit replaced by 1 (OctoMap's adjustKeyAtDepth).
  const OcKey k15 = Grid<OcKey>::key_at_depth(k, 15);
  CHECK(k15[0] == 32768 + 5);
  CHECK(k15[1] == 32768 - 3);
  CHECK(k15[2] == 32768 + 1);
  // Far below the centre at a coarse depth (negative offsets; OctoMap's adjustKeyAtDepth).
  const OcKey low = Grid<OcKey>::key_at_depth(OcKey(100, 100, 100), 5);
  CHECK(low[0] == 1024);  // (100 - 32768) >> 11 = -16; -16 * 2048 + 1024 + 32768
  const OcKey k13 = Grid<OcKey>::key_at_depth(k, 13);
  CHECK(k13[0] == 32768 + 4);
  CHECK(k13[1] == 32768 - 8 + 4);
  CHECK(g.node_size(13) == doctest::Approx(0.8));
  CHECK(g.index_to_coord(k[0], 13) == doctest::Approx(0.4));
  CHECK(g.index_to_coord(k[1], 13) == doctest::Approx(-0.4));
  CHECK(g.index_to_coord(k[0], 0) == 0.0);
  CHECK(g.index_to_coord(k[0], 16) == g.index_to_coord(k[0]));
  // The centre of a coarse node maps back to the coarse key.
  OcKey back;
  REQUIRE(g.coord_to_key(g.index_to_coord(k[0], 13), g.index_to_coord(k[1], 13),
                         g.index_to_coord(k[2], 13), back));
  CHECK(Grid<OcKey>::key_at_depth(back, 13) == k13);
}
