// same_voxels (map/same_voxels.hpp): equal maps whatever their storage order and compaction;
// any difference in the known set or in one value's bits is found.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/map/same_voxels.hpp>

#include "test_support.hpp"

using knnocc::OccupancyMap;
using knnocc::OcKey;

TEST_CASE("same_voxels.storage_order_and_compaction_do_not_matter_one_bit_does") {
  knnocc::test::Rng rng(3);
  std::uniform_int_distribution<int> off(-40, 40);
  std::vector<OcKey> keys;
  for (int i = 0; i < 3000; ++i)
    keys.push_back(OcKey(static_cast<std::uint16_t>(32768 + off(rng)),
                         static_cast<std::uint16_t>(32768 + off(rng)),
                         static_cast<std::uint16_t>(32768 + off(rng))));
  OccupancyMap<OcKey> a(0.1), b(0.1);
  for (const OcKey& k : keys) a.update(k, 0.85f);
  for (auto it = keys.rbegin(); it != keys.rend(); ++it) b.update(*it, 0.85f);  // other order
  CHECK(knnocc::same_voxels(a, b));
  CHECK(knnocc::same_voxels(b, a));
  b.compact();
  CHECK(knnocc::same_voxels(a, b));

  OccupancyMap<OcKey> c(0.1);  // one more voxel
  for (const OcKey& k : keys) c.update(k, 0.85f);
  c.update(OcKey(1000, 1000, 1000), 0.85f);
  CHECK_FALSE(knnocc::same_voxels(a, c));
  CHECK_FALSE(knnocc::same_voxels(c, a));

  OccupancyMap<OcKey> d(0.1);  // one value a bit off
  for (const OcKey& k : keys) d.update(k, 0.85f);
  const float v = *d.logodds(keys[7]);
  d.set(keys[7], std::nextafter(v, -10.0f));
  CHECK_FALSE(knnocc::same_voxels(a, d));

  OccupancyMap<OcKey> e(0.1);  // same count, one voxel elsewhere
  for (std::size_t i = 0; i < keys.size(); ++i)
    e.update(keys[i] == keys[0] ? OcKey(2000, 2000, 2000) : keys[i], 0.85f);
  REQUIRE(e.num_voxels() == a.num_voxels());
  CHECK_FALSE(knnocc::same_voxels(a, e));
}
