// The tracker on real ORB-SLAM2 keyframes (ids present, 4 m cut): after every keyframe the
// incremental state equals the brute-force state.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/knn/tracker.hpp>

#include "test_support.hpp"

TEST_CASE("knn_orbslam.incremental_equals_brute_force") {
  const std::string dir = knnocc::test::data_path("orbslam2_stereo_keyframes");
  if (dir.empty()) {
    MESSAGE("skipped: ../shared/data/orbslam2_stereo_keyframes not available");
    return;
  }
  const auto seq = knnocc::io::Sequence::open(dir);
  REQUIRE(seq.size() == 249);
  knnocc::TrackerParams params;
  params.k = 8;
  params.rebuild_min = 256;  // the static-tree rebuild path runs many times on the way
  knnocc::KnnTracker<> tracker(params);
  std::vector<std::pair<std::uint64_t, knnocc::Point3d>> cloud;  // the map cloud so far
  std::size_t checked_points = 0, wrong = 0;
  std::vector<knnocc::Neighbor> all;
  knnocc::KeyframeUnion map_cloud;
  std::vector<knnocc::Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const auto kf = seq.load_cloud(i);
    REQUIRE(kf.ids.size() == kf.points.size());
    knnocc::io::keyframe_to_world(seq.pose(i), kf, 4.0, world, ids);
    const knnocc::ChangeSet cs = map_cloud.add(world, ids);
    tracker.apply(cs);
    for (const auto& a : cs.added) cloud.emplace_back(a.id, a.p);
    // Brute force for every point of the map cloud.
    for (const auto& [id, p] : cloud) {
      all.clear();
      for (const auto& [jd, q] : cloud)
        if (jd != id) all.push_back({0, jd, knnocc::dist2(q, p)});
      const std::size_t m = std::min(params.k, all.size());
      std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(m), all.end(),
                        [](const knnocc::Neighbor& a, const knnocc::Neighbor& b) {
                          return knnocc::closer(a.d2, a.id, b.d2, b.id);
                        });
      double sum = 0;
      for (std::size_t j = 0; j < m; ++j) sum += std::sqrt(all[j].d2);
      const double s = m == params.k ? sum / double(params.k) : std::nan("");
      const double got = tracker.s(id);
      wrong += !(got == s || (std::isnan(got) && std::isnan(s)));
      ++checked_points;
    }
  }
  MESSAGE(cloud.size() << " map points within 4 m; " << checked_points
                       << " s values compared over 249 keyframes; N " << tracker.N() << " mu "
                       << tracker.mu() << " sigma " << tracker.sigma());
  CHECK(wrong == 0);
  CHECK(tracker.size() == cloud.size());
}
