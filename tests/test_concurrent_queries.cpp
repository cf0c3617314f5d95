// Const queries from many threads while no writer runs: the map (point, depth, box queries,
// iteration, cast_ray), the tracker and the Mapper give every thread the single-threaded answer.
// Built again under ThreadSanitizer by tests/tsan (any report fails tsan.threaded_insertion).

#include <doctest/doctest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include <knnocc/mapper.hpp>
#include <knnocc/raycast/cast_ray.hpp>
#include <knnocc/sensor/knn_model.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

// Everything a reader might ask, folded into one number per query kind.
struct Answers {
  double logodds_sum = 0;
  std::size_t occupied = 0, depth_known = 0, box_voxels = 0, hits = 0, counted = 0;
  double s_sum = 0, mu = 0;
  bool operator==(const Answers& o) const {
    return logodds_sum == o.logodds_sum && occupied == o.occupied && depth_known == o.depth_known &&
           box_voxels == o.box_voxels && hits == o.hits && counted == o.counted &&
           s_sum == o.s_sum && mu == o.mu;
  }
};

template <class MapperT>
Answers ask(const MapperT& mapper, const std::vector<Point3d>& probes) {
  Answers a;
  const auto& map = mapper.map();
  for (const Point3d& p : probes) {
    OcKey k;
    if (!map.grid().coord_to_key(p.x, p.y, p.z, k)) continue;
    if (const auto v = map.logodds(k)) a.logodds_sum += *v;
    a.occupied += map.is_occupied(k).value_or(false);
    a.depth_known += map.logodds_at_depth(k, OcKey::depth - 2).has_value();
    const auto r = cast_ray(map, Point3f{0.0f, 0.0f, 1.2f},
                            Point3f{float(p.x), float(p.y), float(p.z - 1.2)}, false, 6.0);
    a.hits += r.status == CastStatus::occupied;
  }
  map.for_each_voxel_in_bbox(std::array<double, 3>{-1, -1, 0}, std::array<double, 3>{1, 1, 2},
                             [&](const OcKey&, float) { ++a.box_voxels; });
  a.counted = map.count_voxels().occupied;
  const auto& tr = mapper.tracker();
  tr.for_each_point([&](std::uint64_t id, const Point3d&, double s) {
    if (!std::isnan(s)) a.s_sum += s;
    (void)tr.neighbours(id);
  });
  a.mu = tr.mu();
  return a;
}

}  // namespace

TEST_CASE("concurrent_queries.map_tracker_and_mapper_from_many_threads") {
  test::Rng rng(4);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mapper<KnnModel> mapper(0.05);
  for (int f = 0; f < 6; ++f) {
    std::vector<Point3d> pts;
    for (int i = 0; i < 300; ++i) {
      const double a = u(rng) * M_PI, z = 1.0 + 0.5 * u(rng);
      pts.push_back({0.8 * std::cos(a) + 0.02 * u(rng), 0.8 * std::sin(a), z});
    }
    mapper.insert_keyframe(Point3d{0.0, 0.0, 1.2}, pts);
  }
  std::vector<Point3d> probes;
  for (int i = 0; i < 2000; ++i) probes.push_back({u(rng), u(rng), 1.0 + 0.6 * u(rng)});

  const Answers want = ask(mapper, probes);
  CHECK(want.occupied > 0);
  CHECK(want.hits > 0);
  const unsigned n = 4;
  std::vector<Answers> got(n);
  std::atomic<unsigned> ready{0};
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < n; ++t)
    threads.emplace_back([&, t] {
      ++ready;
      while (ready.load() < n) {
      }  // start together, to overlap as much as possible
      for (int rep = 0; rep < 3; ++rep) got[t] = ask(mapper, probes);
    });
  for (auto& th : threads) th.join();
  for (const Answers& g : got) CHECK(g == want);
}
