// SPDX-License-Identifier: BSD-3-Clause
// TileIntegrator (tiles/tile_integrator.hpp) with Mapper::rate (mapper.hpp): every model's rated
// keyframes, integrated tile by tile (each tile given only the keyframes whose keyframe_reach()
// touches it), give the map Mapper builds in one process, voxel for voxel, at several tile
// depths; and Mapper::rate + Mapper::integrate is insert_keyframe. On the simulated tree scene
// (every model, wrong matches that clustered and re-observed, so the robust model's edits take
// evidence back) and on the real stereo ORB-SLAM2 keyframes when present.

#include <doctest/doctest.h>

#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/tree_scene.hpp>
#include <knnocc/tiles/tile_grid.hpp>
#include <knnocc/tiles/tile_integrator.hpp>

#include "test_support.hpp"

using namespace knnocc;

namespace {

// A keyframe in the world frame, as the tool feeds the Mapper.
struct WorldKeyframe {
  Point3d origin;
  std::vector<Point3d> points;
  std::vector<std::uint64_t> ids;
};

std::vector<WorldKeyframe> to_world(const std::vector<io::Pose>& poses,
                                    const std::vector<io::Cloud>& clouds, double crop) {
  std::vector<WorldKeyframe> out;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    WorldKeyframe kf;
    kf.origin = Point3d{poses[i].t.x(), poses[i].t.y(), poses[i].t.z()};
    io::keyframe_to_world(poses[i], clouds[i], crop, kf.points, kf.ids);
    out.push_back(std::move(kf));
  }
  return out;
}

std::vector<WorldKeyframe> tree_scene_keyframes(std::size_t count) {
  sim::TreeSceneParams p;
  p.seed = 7;
  p.keyframes = count;
  p.outlier_cluster = 4;
  p.outlier_repeat = 3;
  sim::TreeScene scene(p);
  std::vector<io::Pose> poses;
  std::vector<io::Cloud> clouds;
  for (const sim::SimKeyframe& kf : scene.keyframes()) {
    poses.push_back(kf.pose);
    clouds.push_back(kf.cloud);
  }
  return to_world(poses, clouds, 4.0);
}

// The map of one Mapper and the same keyframes rated by another, integrated tile by tile at
// `depth`, compared tile by tile; also rate + integrate in a third Mapper.
template <class Model>
void check_tiles(const Model& model, const std::vector<WorldKeyframe>& keyframes, double res,
                 int depth, bool ids = true) {
  CAPTURE(depth);
  MapperOptions mo;
  Mapper<Model> direct(res, model, mo), rater(res, model, mo), split(res, model, mo);
  std::vector<RatedKeyframe> rated(keyframes.size());
  const std::vector<std::uint64_t> none;
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    const WorldKeyframe& kf = keyframes[i];
    direct.insert_keyframe(kf.origin, kf.points, ids ? kf.ids : none);
    rater.rate(kf.origin, kf.points, ids ? kf.ids : none, {}, rated[i]);
    RatedKeyframe again;
    split.rate(kf.origin, kf.points, ids ? kf.ids : none, {}, again);
    split.integrate(again);
  }
  CHECK(test::voxel_values(split.map()) == test::voxel_values(direct.map()));

  const TileGrid<OcKey> tiles(depth);
  const IntegrationParams params = rater.integration();
  std::map<TileCoord, std::vector<std::size_t>> reaching;
  for (std::size_t i = 0; i < rated.size(); ++i)
    if (const auto reach = keyframe_reach(direct.map().grid(), rated[i]))
      tiles.for_each_tile(*reach, [&](const TileCoord& c) { reaching[c].push_back(i); });
  std::map<std::uint64_t, float> joined;
  std::size_t outside = 0;
  for (const auto& [tile, which] : reaching) {
    TileIntegrator<OcKey> t(res, params, tiles.bounds(tile));
    for (const std::size_t i : which) t.integrate(rated[i]);
    t.map().for_each_voxel([&, &c = tile](const OcKey& k, float v) {
      outside += !tiles.bounds(c).contains(k);
      joined[k.pack()] = v;
    });
  }
  CHECK(outside == 0);
  CHECK(joined == test::voxel_values(direct.map()));
  CHECK(direct.map().num_voxels() > 1000);
  if (depth >= 9) CHECK(reaching.size() >= 8);  // the scene spans several tiles
}

}  // namespace

TEST_CASE("tiles: every model's rated keyframes, tile by tile, are the one-process map") {
  // Wrong matches in patches of 4 re-observed by up to 3 keyframes: the robust model takes
  // evidence back (edits) on this scene.
  const std::vector<WorldKeyframe> kfs = tree_scene_keyframes(24);
  std::mt19937 rng(3);
  for (const int depth : {9, 11, 13, 8 + static_cast<int>(rng() % 6)}) {
    check_tiles(OctoMapModel{}, kfs, 0.05, depth);
    check_tiles(KnnModel{}, kfs, 0.05, depth);
    check_tiles(Knn2022Model{}, kfs, 0.05, depth);
    check_tiles(RobustModel{}, kfs, 0.05, depth);
    check_tiles(RobustModel{}, kfs, 0.05, depth, false);  // without ids: OctoMap's rules
  }
  check_tiles(KnnModel{}, kfs, 0.1, 0);  // one tile
}

TEST_CASE("tiles: the stereo ORB-SLAM2 keyframes, every model, tile by tile") {
  const std::string dir = test::data_path("orbslam2_stereo_keyframes");
  if (dir.empty()) {
    test::skip("skipped: ../shared/data/orbslam2_stereo_keyframes not available");
    return;
  }
  const io::ScanSource source = io::ScanSource::open(dir);
  std::vector<io::Pose> poses;
  std::vector<io::Cloud> clouds;
  for (std::size_t i = 0; i < source.size(); ++i) {
    io::Scan s = source.load(i);
    poses.push_back(s.pose);
    clouds.push_back(std::move(s.cloud));
  }
  const std::vector<WorldKeyframe> kfs = to_world(poses, clouds, 4.0);
  for (const int depth : {10, 12}) {
    check_tiles(OctoMapModel{}, kfs, 0.05, depth);
    check_tiles(KnnModel{}, kfs, 0.05, depth);
    check_tiles(Knn2022Model{}, kfs, 0.05, depth);
    check_tiles(RobustModel{}, kfs, 0.05, depth);
  }
}
