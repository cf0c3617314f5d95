// SPDX-License-Identifier: BSD-3-Clause
// A run mapped into tiles (tiles/rating_pass.hpp, tiles/rated_store.hpp, tiles/tile_mapping.hpp,
// tiles/tile_merge.hpp): a sequence folder rated once, each tile mapped from the rated keyframes
// that reach it, the tile set merged: the bytes of the .bt and .ot that Mapper writes in one
// process, for every model, at several tile depths, in 16-bit and wide keys. Rated keyframe files
// read back exactly, and a damaged one is refused.

#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>
#include <knnocc/sim/tree_scene.hpp>
#include <knnocc/tiles/rating_pass.hpp>
#include <knnocc/tiles/tile_mapping.hpp>
#include <knnocc/tiles/tile_merge.hpp>

#include "test_support.hpp"

using namespace knnocc;
namespace fs = std::filesystem;

namespace {

// The tree scene with clustered, re-observed wrong matches as a sequence folder (once).
std::string tree_sequence() {
  const fs::path dir = test::scratch_dir("tile_mapping") / "tree";
  if (fs::exists(dir / "poses.txt")) return dir.string();
  sim::TreeSceneParams p;
  p.seed = 5;
  p.keyframes = 20;
  p.outlier_cluster = 4;
  p.outlier_repeat = 3;
  sim::TreeScene scene(p);
  const std::vector<sim::SimKeyframe> kfs = scene.keyframes();
  std::vector<io::Pose> poses;
  std::vector<const io::Cloud*> clouds;
  for (const sim::SimKeyframe& kf : kfs) {
    poses.push_back(kf.pose);
    clouds.push_back(&kf.cloud);
  }
  io::write_sequence(dir.string(), poses, clouds);
  return dir.string();
}

// The run in one process and in tiles at `depth`; the merged files must be the one-process ones.
template <class Key, class Model>
void check_run(const std::string& seq, const Model& model, double res, int depth, double crop = 4.0,
               std::size_t memory_limit = 0) {
  CAPTURE(depth);
  CAPTURE(memory_limit);
  const io::ScanSource source = io::ScanSource::open(seq);
  auto prepare = [crop](io::Scan& s, std::size_t) {
    std::vector<Point3f> kept;
    io::Cloud& c = s.cloud;
    std::size_t n = 0;
    for (std::size_t j = 0; j < c.points.size(); ++j) {
      const Point3f& q = c.points[j];
      if (!(std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z) <= crop)) continue;
      if (!c.ids.empty()) c.ids[n] = c.ids[j];
      c.points[n++] = q;
    }
    c.points.resize(n);
    if (!c.ids.empty()) c.ids.resize(n);
  };
  Mapper<Model, Key> direct(res, model);
  tiles::WorldScan w;
  for (std::size_t i = 0; i < source.size(); ++i) {
    io::Scan s = source.load(i);
    prepare(s, i);
    w.load<Mapper<Model, Key>>(s);
    w.insert(direct);
  }
  const fs::path root = test::scratch_dir("tile_mapping") / ("run" + std::to_string(depth));
  fs::remove_all(root);
  fs::create_directories(root / "rated");
  fs::create_directories(root / "tiles");
  Mapper<Model, Key> rater(res, model);
  tiles::RatedStoreWriter<Key> writer((root / "rated").string(), res);
  tiles::rate_sequence(source, 0, source.size(), rater, writer, prepare, {});
  CHECK(rater.map().empty());  // the rating pass never touches a map
  const tiles::RatedStore store = tiles::RatedStore::open((root / "rated").string());
  CHECK(store.size() == source.size());
  const tiles::TileSetIndex ix = tiles::write_tile_set<Key>(
      store, (root / "tiles").string(), depth, {"test", "", seq, 0, 20}, 1, memory_limit);
  CHECK(ix.occupied() + ix.free() == direct.map().num_voxels());
  if (memory_limit) CHECK(direct.map().memory_usage() > 2 * memory_limit);  // groups were split
  const std::string bt = (root / "m.bt").string(), ot = (root / "m.ot").string();
  tiles::merge_tile_set((root / "tiles").string(), bt, true);
  tiles::merge_tile_set((root / "tiles").string(), ot, false);
  if constexpr (std::is_same_v<Key, OcKey>) {
    CHECK(test::read_file(bt) == io::encode_bt(direct.map()));
    CHECK(test::read_file(ot) == io::encode_ot(direct.map()));
  } else {  // a wide map: the same voxels at OctoMap's keys
    OccupancyMap<OcKey> narrow(res);
    direct.map().for_each_voxel([&](const Key& k, float v) {
      using I = OcKey::index_type;
      constexpr std::int64_t s = Key::center - OcKey::center;
      narrow.set(
          OcKey(static_cast<I>(k[0] - s), static_cast<I>(k[1] - s), static_cast<I>(k[2] - s)), v);
    });
    CHECK(test::read_file(bt) == io::encode_bt(narrow));
    CHECK(test::read_file(ot) == io::encode_ot(narrow));
  }
  fs::remove_all(root);
}

}  // namespace

TEST_CASE(
    "tile mapping: every model, rated once, mapped tile by tile, merged: the one-process files") {
  const std::string seq = tree_sequence();
  for (const int depth : {0, 10, 12}) {
    check_run<OcKey>(seq, OctoMapModel{}, 0.05, depth);
    check_run<OcKey>(seq, KnnModel{}, 0.05, depth);
    check_run<OcKey>(seq, Knn2022Model{}, 0.05, depth, 100.0);
    check_run<OcKey>(seq, RobustModel{}, 0.05, depth);
  }
  check_run<WideKey>(seq, RobustModel{}, 0.05, 11);
  check_run<WideKey>(seq, OctoMapModel{}, 0.05, 1);
  // Under a memory limit the tiles are mapped in smaller and smaller groups down to single tiles:
  // the same files.
  check_run<OcKey>(seq, OctoMapModel{}, 0.05, 11, 4.0, std::size_t{1} << 20);
  check_run<OcKey>(seq, RobustModel{}, 0.05, 12, 4.0, std::size_t{3} << 18);
}

TEST_CASE("tile mapping: a rated keyframe file reads back exactly; a damaged one is refused") {
  RatedKeyframe rk;
  rk.kind = RatingKind::layered;
  rk.origin = {0.5f, -1.25f, 3.0f};
  for (int i = 0; i < 100; ++i) {
    rk.points.push_back({0.1f * float(i), -0.2f * float(i), std::nanf("")});
    rk.layered.push_back({0.01f * float(i) - 0.5f, i % 2 == 0, static_cast<RayLayer>(i % 3)});
  }
  rk.edits.push_back({123456789, -0.7f, true});
  rk.edits.push_back({42, 0.3f, false});
  const std::string bytes = tiles::encode_rated_keyframe(rk);
  RatedKeyframe back;
  tiles::decode_rated_keyframe("k.rkf", bytes.data(), bytes.size(), back);
  CHECK(tiles::encode_rated_keyframe(back) == bytes);
  CHECK(back.layered[7].ray == RayLayer::strong);
  CHECK(back.edits[0].lower_if_occupied);
  for (std::size_t at : {std::size_t{3}, std::size_t{40}, bytes.size() - 20}) {
    std::string bad = bytes;
    bad[at] = static_cast<char>(bad[at] ^ 4);
    CHECK_THROWS_AS(tiles::decode_rated_keyframe("k.rkf", bad.data(), bad.size(), back), io::Error);
  }
  std::string cut = bytes.substr(0, bytes.size() - 9);
  CHECK_THROWS_WITH_AS(tiles::decode_rated_keyframe("k.rkf", cut.data(), cut.size(), back),
                       doctest::Contains("k.rkf: checksum does not match"), io::Error);
}
