// The tracker on real ORB-SLAM2 keyframes (ids present, 4 m cut): after every keyframe the
// incremental state equals the brute-force state.
#include <doctest/doctest.h>

#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/knn/tracker.hpp>

#include "knn_oracle.hpp"
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
  knnocc::test::Cloud cloud;  // the map cloud so far
  knnocc::KeyframeUnion map_cloud;
  std::vector<knnocc::Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const auto kf = seq.load_cloud(i);
    REQUIRE(kf.ids.size() == kf.points.size());
    knnocc::io::keyframe_to_world(seq.pose(i), kf, 4.0, world, ids);
    const knnocc::ChangeSet cs = map_cloud.add(world, ids);
    tracker.apply(cs);
    for (const auto& a : cs.added) cloud[a.id] = a.p;
    CAPTURE(i);
    knnocc::test::expect_matches(tracker, cloud);  // k-NN sets, s, N, mu, sigma
  }
  MESSAGE(cloud.size() << " map points within 4 m after 249 keyframes; N " << tracker.N() << " mu "
                       << tracker.mu() << " sigma " << tracker.sigma());
}
