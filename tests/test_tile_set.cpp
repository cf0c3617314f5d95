// SPDX-License-Identifier: BSD-3-Clause
// Tile sets on disk (tiles/tile_set.hpp) and their streaming merge (tiles/tile_merge.hpp): a map
// cut into tiles at depths 0 (one tile) to 13 (a brick each) and merged gives the map's own .bt
// and .ot bytes; a tile file is the OctoMap file of its tile alone; a map of wide keys inside
// OctoMap's range merges to the 16-bit map's files, and beyond it is refused with its extent;
// damaged tile sets (a missing tile, a changed byte, a tile of another resolution, an index that
// lies) are one io::Error naming the file, and the output is left as it was.

#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/tiles/tile_merge.hpp>
#include <knnocc/tiles/tile_set.hpp>

#include "test_support.hpp"

using namespace knnocc;
namespace fs = std::filesystem;

namespace {

// The scratch folder of the running test case (ctest runs the cases as parallel processes), and
// its removal when the case ends.
std::string& scratch_root() {
  static std::string root;
  return root;
}
struct Cleanup {
  explicit Cleanup(const std::string& name) {
    scratch_root() = test::scratch_dir("tile_set_" + name).string();
  }
  ~Cleanup() { fs::remove_all(scratch_root()); }
};

// A few scans of scattered and clustered points around two origins, so the map has free space,
// occupied voxels and pruned (uniform) regions across several tiles.
template <class Key>
OccupancyMap<Key> sample_map(double res, Point3f shift = {0, 0, 0}) {
  OccupancyMap<Key> map(res);
  ScanInserter<Key> in(map);
  test::Rng rng(17);
  std::uniform_real_distribution<float> u(-9.0f, 9.0f);
  for (int s = 0; s < 3; ++s) {
    const Point3f o{shift.x + 0.7f * float(s), shift.y - 0.3f, shift.z + 0.2f};
    std::vector<Point3f> pts;
    for (int i = 0; i < 4000; ++i)
      pts.push_back({shift.x + u(rng), shift.y + u(rng), shift.z + 0.3f * u(rng)});
    for (int i = 0; i < 400; ++i)  // a wall
      pts.push_back(
          {shift.x + 6.0f, shift.y + 0.02f * float(i % 40), shift.z + 0.05f * float(i / 40)});
    in.insert_point_cloud(o, pts);
  }
  return map;
}

// `map` cut into tiles at `depth` into a fresh folder; returns the folder.
template <class Key>
std::string write_tiles(const OccupancyMap<Key>& map, int depth, const std::string& name) {
  const fs::path dir = fs::path(scratch_root()) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  const TileGrid<Key> grid(depth);
  tiles::TileSetIndex ix;
  ix.resolution = map.resolution();
  ix.key_bits = Key::depth;
  ix.tile_depth = depth;
  ix.params.occupancy = map.params();
  ix.model = "octomap";
  ix.tiles = tiles::write_tiles_of(map, dir.string(), grid);
  tiles::write_index(dir.string(), ix);
  return dir.string();
}

std::string merged(const std::string& dir, bool binary) {
  const std::string out = dir + (binary ? ".merged.bt" : ".merged.ot");
  tiles::merge_tile_set(dir, out, binary);
  return test::read_file(out);
}

}  // namespace

TEST_CASE("tile set: cut at any depth and merged, the map's own .bt and .ot bytes") {
  const Cleanup cleanup("cut");
  const OccupancyMap<OcKey> map = sample_map<OcKey>(0.1);
  const std::string bt = io::encode_bt(map), ot = io::encode_ot(map);
  std::mt19937 rng(11);
  for (const int depth : {0, 1, 5, 9, 11, 2 + static_cast<int>(rng() % 11)}) {
    CAPTURE(depth);
    const std::string dir = write_tiles(map, depth, "d" + std::to_string(depth));
    CHECK(merged(dir, true) == bt);
    CHECK(merged(dir, false) == ot);
    const tiles::TileSetIndex ix = tiles::read_index(dir);
    CHECK(ix.occupied() + ix.free() == map.num_voxels());
    if (depth >= 10) CHECK(ix.tiles.size() > 8);
  }
  // Tiles of one brick each, on a corner of the map.
  OccupancyMap<OcKey> corner(0.1);
  const OcKey lo(32740, 32730, 32760), hi(32800, 32790, 32775);
  map.for_each_voxel_in_bbox(lo, hi, [&](const OcKey& k, float v) { corner.set(k, v); });
  const std::string dir = write_tiles(corner, 13, "d13");
  CHECK(tiles::read_index(dir).tiles.size() > 50);
  CHECK(merged(dir, true) == io::encode_bt(corner));
  CHECK(merged(dir, false) == io::encode_ot(corner));
}

TEST_CASE("tile set: a tile's file is the OctoMap file of that tile alone") {
  const Cleanup cleanup("alone");
  const OccupancyMap<OcKey> map = sample_map<OcKey>(0.1);
  const int depth = 10;
  const std::string dir = write_tiles(map, depth, "alone");
  const tiles::TileSetIndex ix = tiles::read_index(dir);
  const TileGrid<OcKey> grid(depth);
  for (const tiles::TileEntry& e : ix.tiles) {
    OccupancyMap<OcKey> only(map.resolution());
    const KeyBounds<OcKey> b = grid.bounds(e.coord);
    map.for_each_voxel_in_bbox(b.lo, b.hi, [&](const OcKey& k, float v) { only.set(k, v); });
    CHECK(test::read_file(fs::path(dir) / e.file) == io::encode_ot(only));
    CHECK(test::voxel_values(tiles::read_tile<OcKey>(dir, ix, e)) == test::voxel_values(only));
  }
}

TEST_CASE("tile set: wide keys inside OctoMap's range merge to the 16-bit map's files") {
  const Cleanup cleanup("wide");
  const OccupancyMap<OcKey> narrow = sample_map<OcKey>(0.1, {-1500.0f, 2200.0f, -3.0f});
  const OccupancyMap<WideKey> wide = sample_map<WideKey>(0.1, {-1500.0f, 2200.0f, -3.0f});
  for (const int depth : {1, 6, 12}) {
    CAPTURE(depth);
    const std::string dir = write_tiles(wide, depth, "wide" + std::to_string(depth));
    CHECK(merged(dir, true) == io::encode_bt(narrow));
    CHECK(merged(dir, false) == io::encode_ot(narrow));
    const tiles::TileSetIndex ix = tiles::read_index(dir);
    CHECK(ix.key_bits == 21);
    for (const tiles::TileEntry& e : ix.tiles)  // read back at the wide keys
      for (std::size_t a = 0; a < 3; ++a) CHECK(e.shift[a] == WideKey::center - 32768);
  }
}

TEST_CASE("tile set: wide keys beyond OctoMap's range are kept as tiles, merging is refused") {
  const Cleanup cleanup("far");
  const OccupancyMap<WideKey> wide = sample_map<WideKey>(0.1, {5000.0f, -7000.0f, 0.0f});
  const std::string dir = write_tiles(wide, 8, "far");
  const tiles::TileSetIndex ix = tiles::read_index(dir);
  std::map<std::uint64_t, float> back;
  for (const tiles::TileEntry& e : ix.tiles) {
    for (const std::int64_t s : e.shift) CHECK(s % 65536 == (WideKey::center - 32768) % 65536);
    const OccupancyMap<WideKey> t = tiles::read_tile<WideKey>(dir, ix, e);
    t.for_each_voxel([&](const WideKey& k, float v) { back[k.pack()] = v; });
  }
  CHECK(back == test::voxel_values(wide));
  const std::string out = dir + ".merged.bt";
  CHECK_THROWS_WITH_AS(tiles::merge_tile_set(dir, out, true),
                       doctest::Contains("beyond the +-3276.8 m an OctoMap .bt/.ot holds"),
                       io::Error);
  CHECK_FALSE(fs::exists(out));
}

TEST_CASE("tile set: a damaged tile set is one io::Error naming the file, nothing written") {
  const Cleanup cleanup("damaged");
  const OccupancyMap<OcKey> map = sample_map<OcKey>(0.1);
  const OccupancyMap<OcKey> coarse = sample_map<OcKey>(0.2);
  struct Damage {
    const char* name;
    const char* message;
    void (*apply)(const std::string& dir, const tiles::TileSetIndex& ix);
  };
  static std::string coarse_tile;  // a tile file of another resolution
  coarse_tile = io::encode_ot(coarse);
  const Damage damages[] = {
      {"missing tile", "missing: the tile set's index lists it",
       [](const std::string& dir, const tiles::TileSetIndex& ix) {
         fs::remove(fs::path(dir) / ix.tiles[3].file);
       }},
      {"changed byte", "sha256 does not match the index",
       [](const std::string& dir, const tiles::TileSetIndex& ix) {
         const fs::path p = fs::path(dir) / ix.tiles[2].file;
         std::string b = test::read_file(p);
         b[b.size() - 3] = static_cast<char>(b[b.size() - 3] ^ 1);
         test::write_file(p, b);
       }},
      {"another resolution", "differs from the tile set's 0.1",
       [](const std::string& dir, const tiles::TileSetIndex& ix) {
         tiles::TileSetIndex lie = ix;
         test::write_file(fs::path(dir) / ix.tiles[1].file, coarse_tile);
         lie.tiles[1].bytes = coarse_tile.size();
         io::detail::Sha256 h;
         h.update(coarse_tile);
         lie.tiles[1].sha256 = h.hex();
         tiles::write_index(dir, lie);
       }},
      {"index lies about a node count", "does not match the index's summary",
       [](const std::string& dir, const tiles::TileSetIndex& ix) {
         tiles::TileSetIndex lie = ix;
         lie.tiles[0].bt.nodes += 1;
         lie.tiles[0].ot.nodes += 1;
         tiles::write_index(dir, lie);
       }},
      {"index lies about counts", "free voxels, the index says",
       [](const std::string& dir, const tiles::TileSetIndex& ix) {
         tiles::TileSetIndex lie = ix;
         lie.tiles[0].occupied += 1;
         tiles::write_index(dir, lie);
       }},
      {"index lies about keys", "do not match its coordinates",
       [](const std::string& dir, const tiles::TileSetIndex&) {
         std::string text = test::read_file(fs::path(dir) / "index.txt");
         const auto at = text.find(" keys ") + 6;
         text.insert(at, "1");
         test::write_file(fs::path(dir) / "index.txt", text);
       }},
      {"index lists fewer tiles", "the index lists",
       [](const std::string& dir, const tiles::TileSetIndex&) {
         std::string text = test::read_file(fs::path(dir) / "index.txt");
         const auto at = text.find("\ntiles ") + 7;
         text.insert(at, "1");
         test::write_file(fs::path(dir) / "index.txt", text);
       }},
  };
  for (const Damage& d : damages) {
    CAPTURE(std::string(d.name));
    const std::string dir = write_tiles(map, 9, std::string("bad_") + d.name);
    const tiles::TileSetIndex ix = tiles::read_index(dir);
    REQUIRE(ix.tiles.size() > 4);
    d.apply(dir, ix);
    // What `knnocc info` checks: every tile read, and its trees against the index.
    const auto check_all = [&dir] {
      const tiles::TileSetIndex now = tiles::read_index(dir);
      for (const tiles::TileEntry& e : now.tiles)
        tiles::check_tile_nodes(dir, now, e, tiles::read_tile<OcKey>(dir, now, e));
    };
    CHECK_THROWS_WITH_AS(check_all(), doctest::Contains(d.message), io::Error);
    for (const bool binary : {true, false}) {
      const std::string out = dir + (binary ? ".bt" : ".ot");
      test::write_file(out, "old");
      CHECK_THROWS_WITH_AS(tiles::merge_tile_set(dir, out, binary), doctest::Contains(d.message),
                           io::Error);
      CHECK(test::read_file(out) == "old");
      CHECK_FALSE(test::has_temporary_beside(out));
    }
  }
}
