// The core headers built with -fno-exceptions -fno-rtti and KNNOCC_NO_HUGE_PAGES (embedded
// builds): keys, map, DDA, both sensor models, Welford, tracker and mapper work; a caller error
// prints one line and aborts.
//   knnocc_noexcept_smoke            runs the smoke checks, exit 0
//   knnocc_noexcept_smoke invalid    passes an invalid k-NN parameter: message, then abort()

#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <knnocc/knnocc.hpp>

#if KNNOCC_HAS_EXCEPTIONS
#error "this file must be compiled with -fno-exceptions"
#endif

#define SMOKE_CHECK(cond)                                                          \
  do {                                                                             \
    if (!(cond)) {                                                                 \
      std::fprintf(stderr, "smoke check failed: %s (line %d)\n", #cond, __LINE__); \
      return 1;                                                                    \
    }                                                                              \
  } while (0)

int main(int argc, char** argv) {
  using namespace knnocc;
  if (argc > 1 && !std::strcmp(argv[1], "invalid")) {
    KnnModelParams p;
    p.p_w = 0.4;
    KnnModel model(p);  // aborts with "knnocc: P_w must be in (0.5, 1), got 0.400000"
    return 0;
  }

  // Keys and the map.
  OccupancyMap<OcKey> map(0.1);
  OcKey k;
  SMOKE_CHECK(map.grid().coord_to_key(1.05, -2.05, 0.35, k));
  SMOKE_CHECK(OcKey::unpack(k.pack()) == k);
  map.update(k, logodds(0.7));
  SMOKE_CHECK(map.is_occupied(k).value_or(false));

  // DDA.
  std::vector<OcKey> ray;
  SMOKE_CHECK(compute_ray_keys(map.grid(), Point3f{0.05f, 0.05f, 0.05f},
                               Point3f{1.05f, 0.05f, 0.05f}, ray));
  SMOKE_CHECK(ray.size() == 10);

  // Welford.
  RunningNormal d;
  for (double v : {1.0, 2.0, 3.0, 4.0}) d.add(v);
  d.erase(4.0);
  SMOKE_CHECK(std::fabs(d.mean() - 2.0) < 1e-12);

  // OctoMap model through the mapper.
  std::vector<Point3d> pts;
  for (int i = 0; i < 40; ++i) pts.push_back({2.0 + 0.02 * i, 0.3 + 0.01 * (i % 5), 0.2});
  Mapper<OctoMapModel> octo(0.1);
  octo.insert_keyframe(Point3d{0, 0, 0}, pts);
  SMOKE_CHECK(octo.map().count_voxels().occupied > 0);

  // A scan large enough to go in chunks, with large scratch blocks (malloc here, not mmap).
  std::vector<Point3f> scan;
  for (int i = 0; i < 20000; ++i)
    scan.push_back({8.0f + 0.001f * static_cast<float>(i % 97),
                    -6.0f + 0.0006f * static_cast<float>(i), 0.3f * static_cast<float>(i % 7)});
  OccupancyMap<OcKey> big(0.05);
  ScanInserter<OcKey> inserter(big);
  const ScanStats st = inserter.insert_point_cloud(Point3f{0.0f, 0.0f, 1.0f}, scan);
  constexpr std::size_t kChunk = ScanInserter<OcKey>::chunk_points;
  SMOKE_CHECK(st.chunks == (scan.size() + kChunk - 1) / kChunk);
  SMOKE_CHECK(st.chunks > 1);
  SMOKE_CHECK(st.ray_keys > 2000000);
  big.compact();
  SMOKE_CHECK(big.count_voxels().free > 10000);

  // k-NN model: tracker + mapper.
  Mapper<KnnModel> knn(0.1);
  const KeyframeStats ks = knn.insert_keyframe(Point3d{0, 0, 0}, pts);
  SMOKE_CHECK(knn.tracker().size() == pts.size());
  SMOKE_CHECK(ks.rated == pts.size());
  SMOKE_CHECK(knn.map().count_voxels().free > 0);
  std::printf("noexcept smoke: ok (%zu voxels)\n", knn.map().num_voxels());
  return 0;
}
