// The map's value arrays (map/value_pool.hpp), and compaction that gives them back.
#include <doctest/doctest.h>

#include <cstdint>
#include <set>
#include <vector>

#include <knnocc/map/occupancy_map.hpp>

using knnocc::OcKey;

TEST_CASE("memory.value_pool_hands_out_distinct_arrays_and_reuses_released_ones") {
  knnocc::ValuePool pool;
  CHECK(pool.memory_usage() == 0);
  std::vector<float*> arrays;
  std::set<float*> distinct;
  // Across several slabs, the first ones small and the later ones 2 MB.
  for (int i = 0; i < 5000; ++i) {
    float* a = pool.allocate();
    for (int k = 0; k < knnocc::kBrickVoxels; ++k) a[k] = static_cast<float>(i);
    arrays.push_back(a);
    distinct.insert(a);
  }
  CHECK(distinct.size() == arrays.size());
  bool intact = true;  // no array overlaps another
  for (std::size_t i = 0; i < arrays.size(); ++i)
    for (int k = 0; k < knnocc::kBrickVoxels; k += 97)
      intact = intact && arrays[i][k] == static_cast<float>(i);
  CHECK(intact);
  const std::size_t reserved = pool.memory_usage();
  CHECK(reserved >= 5000 * knnocc::ValuePool::kArrayBytes);
  CHECK(reserved <= 5000 * knnocc::ValuePool::kArrayBytes + knnocc::detail::kHugePage + 4096);

  pool.release(arrays[7]);
  pool.release(arrays[9]);
  float* again = pool.allocate();
  CHECK((again == arrays[9] || again == arrays[7]));

  knnocc::ValuePool moved = std::move(pool);  // arrays stay where they are
  CHECK(arrays[100][0] == 100.0f);
  moved.clear();
  CHECK(moved.memory_usage() == 0);
}

TEST_CASE("memory.compaction_gives_value_arrays_back") {
  // Many bricks with one value each compact to nothing; the few mixed ones keep their values.
  knnocc::OccupancyMap<OcKey> map(0.1);
  for (std::uint16_t b = 0; b < 200; ++b)
    for (std::uint16_t i = 0; i < 8; ++i)
      map.update(OcKey(static_cast<std::uint16_t>(32768 + 8 * b + i), 32768, 32768), -0.4f);
  map.update(OcKey(32768, 32768, 32768), 0.85f);  // brick 0 now holds two values
  const std::size_t before = map.memory_usage();
  CHECK(map.compact() == 199);
  CHECK(map.memory_usage() + 199 * knnocc::ValuePool::kArrayBytes / 2 < before);
  CHECK(*map.logodds(OcKey(32768, 32768, 32768)) == doctest::Approx(0.45f));
  CHECK(*map.logodds(OcKey(32769, 32768, 32768)) == -0.4f);
  CHECK(*map.logodds(OcKey(32768 + 8 * 150 + 3, 32768, 32768)) == -0.4f);
  // Compacted bricks take arrays again when they are written.
  map.update(OcKey(32768 + 8 * 150 + 3, 32768, 32768), 1.0f);
  CHECK(*map.logodds(OcKey(32768 + 8 * 150 + 3, 32768, 32768)) == doctest::Approx(0.6f));
  CHECK(*map.logodds(OcKey(32768 + 8 * 150 + 4, 32768, 32768)) == -0.4f);
  CHECK(map.num_voxels() == 1600);
}
