// OctoMap .bt/.ot files: byte-exact round trip of the real geb079.bt, liboctomap (when found) as
// the oracle for the bytes we write and for reading them back, and malformed files.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/xyz.hpp>

#include "test_support.hpp"

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>
#include <octomap/OcTreeStamped.h>

#include "octomap_oracle.hpp"
#endif

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::OccupancyMap;
using knnocc::OcKey;
using knnocc::Point3f;

using knnocc::test::read_file;
using knnocc::test::write_file;

namespace {

std::string tree_file(const std::string& name) {
  return knnocc::test::scratch_file("octomap_tree", name);
}

// Every known voxel of a equals b's (and the counts match), values compared exactly.
void check_same_voxels(const OccupancyMap<OcKey>& a, const OccupancyMap<OcKey>& b) {
  CHECK(a.num_voxels() == b.num_voxels());
  std::size_t differing = 0;
  a.for_each_voxel([&](const OcKey& k, float v) {
    const auto w = b.logodds(k);
    differing += !w || *w != v;
  });
  CHECK(differing == 0);
}

// A map with dense uniform blocks (pruned at several depths), mixed blocks, free space around,
// and single voxels at the key range's edges.
OccupancyMap<OcKey> mixed_map(std::uint64_t seed) {
  OccupancyMap<OcKey> map(0.05);
  const auto& p = map.params();
  knnocc::test::Rng rng(seed);
  std::uniform_int_distribution<int> coord(32700, 32830), pick(0, 3);
  for (int block = 0; block < 12; ++block) {
    const int edge = 1 << (1 + block % 4);  // 2..16 voxels
    const int x0 = coord(rng) & ~(edge - 1), y0 = coord(rng) & ~(edge - 1),
              z0 = coord(rng) & ~(edge - 1);
    const int kind = pick(rng);
    for (int x = 0; x < edge; ++x)
      for (int y = 0; y < edge; ++y)
        for (int z = 0; z < edge; ++z) {
          const OcKey k(static_cast<std::uint16_t>(x0 + x), static_cast<std::uint16_t>(y0 + y),
                        static_cast<std::uint16_t>(z0 + z));
          float v = kind == 0 ? p.clamp_max : kind == 1 ? p.clamp_min : -0.4f;
          if (kind == 3) v = (x + y + z) % 3 ? 0.85f : -1.2f;
          map.set(k, v);
        }
  }
  std::uniform_real_distribution<float> val(-2.f, 3.5f);
  for (int i = 0; i < 3000; ++i)
    map.set(OcKey(static_cast<std::uint16_t>(coord(rng)), static_cast<std::uint16_t>(coord(rng)),
                  static_cast<std::uint16_t>(coord(rng))),
            val(rng));
  map.set(OcKey(0, 0, 0), 1.0f);
  map.set(OcKey(65535, 65535, 65535), -1.0f);
  return map;
}

}  // namespace

TEST_CASE("octomap_tree.geb079 round trip gives identical bytes") {
  const std::string path = knnocc::test::data_path("octomap_fr079/geb079.bt");
  if (path.empty()) {
    knnocc::test::skip("skipped: ../shared/data/octomap_fr079/geb079.bt not available");
    return;
  }
  const io::OctreeInfo info = io::inspect_octree(path);
  CHECK(info.binary);
  CHECK(info.id == "OcTree");
  CHECK(info.resolution == doctest::Approx(0.08));
  CHECK(info.nodes == 532566);  // ../shared/data/README.md
  CHECK(info.occupied_leaves == 143729);
  CHECK(info.free_leaves == 284415);
  CHECK(info.min_leaf_depth == 13);

  const OccupancyMap<OcKey> map = io::read_octree(path);
  const auto counts = map.count_voxels();
  CHECK(counts.occupied == info.occupied_voxels);
  CHECK(counts.free == info.free_voxels);
  CHECK(map.num_voxels() == 1136432);
  MESSAGE("geb079: " << counts.occupied << " occupied, " << counts.free
                     << " free finest voxels; map memory " << map.memory_usage() / 1e6 << " MB");

  const std::string original = read_file(path);
  const std::string ours = io::encode_bt(map);
  CHECK(ours.size() == original.size());
  CHECK(ours == original);
  const std::string out = tree_file("geb079_copy.bt");
  io::write_bt(out, map);
  CHECK(read_file(out) == original);
  CHECK_FALSE(knnocc::test::has_temporary_beside(out));

  // .ot of the same map, read back: the same voxels and values.
  const std::string ot = tree_file("geb079.ot");
  io::write_ot(ot, map);
  check_same_voxels(map, io::read_octree(ot));
}

TEST_CASE("octomap_tree.round trips of a mixed map") {
  const OccupancyMap<OcKey> map = mixed_map(7);
  const std::string ot = tree_file("mixed.ot"), bt = tree_file("mixed.bt");
  io::write_ot(ot, map);
  io::write_bt(bt, map);
  const auto back = io::read_octree(ot);
  CHECK(back.resolution() == 0.05);
  check_same_voxels(map, back);
  CHECK(io::encode_ot(back) == read_file(ot));

  // .bt keeps occupancy only: every voxel comes back at the clamp bound of its class.
  const auto bin = io::read_octree(bt);
  CHECK(bin.num_voxels() == map.num_voxels());
  std::size_t wrong = 0;
  map.for_each_voxel([&](const OcKey& k, float v) {
    const auto w = bin.logodds(k);
    const float expect = map.is_occupied(v) ? map.params().clamp_max : map.params().clamp_min;
    wrong += !w || *w != expect;
  });
  CHECK(wrong == 0);
  CHECK(io::encode_bt(bin) == read_file(bt));

  // Pruned nodes exist (uniform blocks): fewer nodes than voxels would need.
  const io::OctreeInfo info = io::inspect_octree(bt);
  CHECK(info.min_leaf_depth < 16);
  CHECK(info.occupied_voxels + info.free_voxels == map.num_voxels());
}

TEST_CASE("octomap_tree.a note rides in a header comment and reads back") {
  const OccupancyMap<OcKey> map = mixed_map(3);
  const std::string note = "map: clouds 0 to 4 of seq\n\x1b;";
  const std::string bt = tree_file("note.bt"), ot = tree_file("note.ot");
  io::write_bt(bt, map, note);
  io::write_ot(ot, map, note);
  for (const std::string& path : {bt, ot}) {
    CAPTURE(path);
    const std::string bytes = read_file(path);
    // One comment line after OctoMap's, control bytes escaped: the header stays a header.
    CHECK(bytes.find("#\n# knnocc map: clouds 0 to 4 of seq\\x0a\\x1b;\nid OcTree\n") !=
          std::string::npos);
    CHECK(io::inspect_octree(path).note == "map: clouds 0 to 4 of seq\\x0a\\x1b;");
    CHECK(io::read_octree(path).num_voxels() == map.num_voxels());
  }
  // Without the comment the bytes are the note-free encoding's.
  std::string plain = read_file(ot);
  const std::size_t at = plain.find("# knnocc");
  plain.erase(at, plain.find('\n', at) + 1 - at);
  CHECK(plain == io::encode_ot(map));
  check_same_voxels(map, io::read_octree(ot));
  write_file(tree_file("no_note.ot"), plain);
  CHECK(io::inspect_octree(tree_file("no_note.ot")).note.empty());
}

TEST_CASE("octomap_tree.empty map") {
  const OccupancyMap<OcKey> empty(0.1);
  const std::string bt = io::encode_bt(empty);
  CHECK(bt.find("size 0\nres 0.1\ndata\n") != std::string::npos);
  const std::string path = tree_file("empty.bt");
  write_file(path, bt);
  CHECK(io::read_octree(path).num_voxels() == 0);
}

TEST_CASE("octomap_tree.malformed files throw io::Error naming the file") {
  const OccupancyMap<OcKey> map = mixed_map(3);
  const std::string good_bt = io::encode_bt(map), good_ot = io::encode_ot(map);
  const std::size_t bt_data = good_bt.find("data\n") + 5, ot_data = good_ot.find("data\n") + 5;
  const std::string header_bt = good_bt.substr(0, bt_data);
  auto expect_error = [&](const std::string& name, const std::string& bytes,
                          const std::string& needle, bool inspect_fails = true) {
    CAPTURE(name);
    const std::string path = tree_file(name);
    write_file(path, bytes);
    try {
      (void)io::read_octree(path);
      FAIL("no error for " << name);
    } catch (const io::Error& e) {
      CHECK(e.file() == path);
      CHECK_MESSAGE(e.problem().find(needle) != std::string::npos, e.problem());
    }
    if (!inspect_fails) return;  // a limit of reading, not a malformed file
    try {
      (void)io::inspect_octree(path);
      FAIL("inspect: no error for " << name);
    } catch (const io::Error& e) {
      CHECK(e.file() == path);
    }
  };
  auto replace = [](std::string s, const std::string& from, const std::string& to) {
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  expect_error("truncated.bt", good_bt.substr(0, good_bt.size() - 7), "truncated");
  expect_error("truncated.ot", good_ot.substr(0, ot_data + 12), "truncated");
  expect_error("header_only.bt", header_bt, "truncated");
  expect_error("trailing.bt", good_bt + "xyz", "unexpected bytes");
  expect_error("not_octomap.bt", "ply\nformat ascii 1.0\n", "not an OctoMap file");
  expect_error("no_data.bt", replace(header_bt, "data\n", ""), "no 'data' line");
  expect_error("no_res.ot", replace(good_ot, "res 0.05\n", ""), "no 'res' line");
  expect_error("zero_res.bt", replace(good_bt, "res 0.05", "res 0"), "invalid resolution");
  expect_error("nan_res.bt", replace(good_bt, "res 0.05", "res nan"), "invalid resolution");
  // Finite, but a map cannot hold it: voxel centres would overflow float (a page of -inf, a
  // PLY of inf points), or the voxels are below the 1e-6 m a Grid takes.
  expect_error("huge_res.bt", replace(good_bt, "res 0.05", "res 1e308"),
               "resolution 1e+308 is above 1.03846e+34 m: the key range");
  expect_error("huge_res.ot", replace(good_ot, "res 0.05", "res 2e34"), "the key range");
  expect_error("tiny_res.bt", replace(good_bt, "res 0.05", "res 1e-9"),
               "resolution 1e-09 is below 1e-06 m");
  // A control byte or a NUL in a header word is shown escaped, and the message goes on.
  expect_error("escape_id.ot", replace(good_ot, "id OcTree", std::string("id Oc\x1b[2J\0Tree", 14)),
               "'Oc\\x1b[2J\\x00Tree'");
  expect_error("text_size.bt", replace(good_bt, "size ", "size x"), "invalid node count");
  expect_error("huge_size.bt", replace(good_bt, "size ", "size 9"), "but the tree has");
  expect_error("bad_id.ot", replace(good_ot, "id OcTree", "id CountingOcTree"),
               "unsupported OctoMap tree type");
  expect_error("keyword.bt", replace(good_bt, "id OcTree", "colour red"), "unknown header keyword");
  // Headers are bounded: 200,000 comment lines (2.4 MB) are refused at 1 MiB, quickly.
  std::string comments;
  for (int i = 0; i < 200000; ++i) comments += "# comment\n";
  expect_error("long_header.bt", replace(good_bt, "id OcTree", comments + "id OcTree"),
               "OctoMap header is longer than 1 MiB");

  // Hand-built node streams.
  const std::string bt_head = std::string(io::detail::kBtFirstLine) + "\n";
  const std::string ot_head = std::string(io::detail::kOtFirstLine) + "\n";
  // Root with 8 free leaves at depth 1: 2^48 finest voxels claimed by 2 bytes of data.
  expect_error("absurd.bt", bt_head + "id OcTree\nsize 9\nres 0.1\ndata\n\x55\x55",
               "OctreeReadOptions::max_voxels", false);
  // A chain of "has children" down to depth 16 and one level further.
  std::string chain;
  for (int d = 0; d < 16; ++d) chain += std::string("\x03\x00", 2);
  expect_error("too_deep.bt", bt_head + "id OcTree\nsize 17\nres 0.1\ndata\n" + chain, "depth 16");
  // .ot root holding NaN.
  const float nan = std::nanf("");
  std::string nan_node(5, '\0');
  std::memcpy(&nan_node[0], &nan, 4);
  expect_error("nan.ot", ot_head + "id OcTree\nsize 1\nres 0.1\ndata\n" + nan_node, "non-finite");
  // More nodes than the size line: stops at the claim.
  expect_error("short_size.ot", replace(good_ot, "size ", "size 1"), "");
}

TEST_CASE("octomap_tree.max_voxels bounds the expansion of pruned leaves") {
  OccupancyMap<OcKey> map(0.1);
  for (std::uint16_t x = 0; x < 16; ++x)
    for (std::uint16_t y = 0; y < 16; ++y)
      for (std::uint16_t z = 0; z < 16; ++z)
        map.set(OcKey(static_cast<std::uint16_t>(32768 + x), static_cast<std::uint16_t>(32768 + y),
                      static_cast<std::uint16_t>(32768 + z)),
                2.0f);
  const std::string path = tree_file("cube.bt");
  io::write_bt(path, map);
  const io::OctreeInfo info = io::inspect_octree(path);
  CHECK(info.min_leaf_depth == 12);  // one leaf of 16^3 voxels
  CHECK(info.occupied_leaves == 1);
  CHECK(info.nodes == 13);
  io::OctreeReadOptions small;
  small.max_voxels = 4095;
  CHECK_THROWS_AS(io::read_octree(path, small), io::Error);
  small.max_voxels = 4096;
  const auto back = io::read_octree(path, small);
  CHECK(back.num_voxels() == 4096);
  CHECK(back.num_bricks() == 8);
}

#if KNNOCC_HAVE_OCTOMAP
namespace {

// liboctomap's leaves, expanded to finest voxels, against our map (value compared exactly when
// `values`, else by occupancy class).
void check_octomap_sees(const octomap::OcTree& tree, const OccupancyMap<OcKey>& ours, bool values) {
  std::size_t finest = 0, wrong = 0, occupied = 0;
  knnocc::test::for_each_octomap_voxel(tree, [&](const OcKey& k, const octomap::OcTreeNode& leaf) {
    ++finest;
    occupied += tree.isNodeOccupied(leaf);
    const auto got = ours.logodds(k);
    if (!got)
      ++wrong;
    else if (values)
      wrong += *got != leaf.getLogOdds();
    else
      wrong += ours.is_occupied(*got) != tree.isNodeOccupied(leaf);
  });
  const auto counts = ours.count_voxels();
  MESSAGE("liboctomap sees " << tree.getNumLeafNodes() << " leaves, " << finest
                             << " finest voxels (" << occupied << " occupied)");
  CHECK(wrong == 0);
  CHECK(finest == ours.num_voxels());
  CHECK(occupied == counts.occupied);
}

std::string octomap_bytes(octomap::OcTree& tree, bool binary) {
  std::ostringstream s;
  if (binary)
    tree.writeBinary(s);  // makes the tree max-likelihood and prunes it
  else
    tree.write(s);
  return s.str();
}

}  // namespace

TEST_CASE("octomap_tree.liboctomap writes the same bytes and reads ours (scan.dat)") {
  const auto points = knnocc::test::scan_dat_points_or_skip();
  if (points.empty()) return;
  OccupancyMap<OcKey> map(0.1);
  knnocc::ScanInserter<OcKey>(map).insert_point_cloud(Point3f{}, points, -1.0, false);

  octomap::OcTree tree(0.1);
  octomap::Pointcloud pc;
  for (const auto& p : points) pc.push_back(p.x, p.y, p.z);
  tree.insertPointCloud(pc, octomap::point3d(0, 0, 0));
  CHECK(tree.size() == 407411);  // ../shared/data/README.md

  const std::string ot = io::encode_ot(map);
  CHECK(ot.find("size 407411\n") != std::string::npos);
  CHECK(ot == octomap_bytes(tree, false));
  const std::string bt = io::encode_bt(map);
  CHECK(bt == octomap_bytes(tree, true));

  // liboctomap reads our files and sees our leaves.
  const std::string ot_path = tree_file("scan_dat.ot"), bt_path = tree_file("scan_dat.bt");
  io::write_ot(ot_path, map);
  io::write_bt(bt_path, map);
  {
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(ot_path));
    auto* t = dynamic_cast<octomap::OcTree*>(read.get());
    REQUIRE(t != nullptr);
    CHECK(t->size() == 407411);
    check_octomap_sees(*t, map, true);
  }
  {
    octomap::OcTree t(0.1);
    REQUIRE(t.readBinary(bt_path));
    CHECK(t.getNumLeafNodes() > 0);
    check_octomap_sees(t, map, false);
  }
}

TEST_CASE("octomap_tree.liboctomap skips the note's comment line") {
  const OccupancyMap<OcKey> map = mixed_map(4);
  const std::string bt = tree_file("note_octomap.bt"), ot = tree_file("note_octomap.ot");
  io::write_bt(bt, map, "map: clouds 0 to 9 of seq; continue with --first 10");
  io::write_ot(ot, map, "map: clouds 0 to 9 of seq; continue with --first 10");
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(ot));
  auto* t = dynamic_cast<octomap::OcTree*>(read.get());
  REQUIRE(t != nullptr);
  check_octomap_sees(*t, map, true);
  octomap::OcTree b(0.05);
  REQUIRE(b.readBinary(bt));
  check_octomap_sees(b, map, false);
}

TEST_CASE("octomap_tree.liboctomap agrees on mixed maps, pruning included") {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    CAPTURE(seed);
    const OccupancyMap<OcKey> map = mixed_map(seed);
    octomap::OcTree tree(0.05);
    map.for_each_voxel([&](const OcKey& k, float v) {
      tree.setNodeValue(octomap::OcTreeKey(k[0], k[1], k[2]), v);
    });
    CHECK(io::encode_ot(map) == octomap_bytes(tree, false));
    CHECK(io::encode_bt(map) == octomap_bytes(tree, true));
  }
}

namespace {

// A colour per voxel of mixed_map: one per aligned 2x2x2 block (so the 8 leaves of some nodes
// are equal in value and colour and those of larger nodes are not), none for some voxels.
std::optional<knnocc::Rgb> test_color(const OcKey& k) {
  if ((k[0] + 3 * k[1]) % 11 == 0) return std::nullopt;
  return knnocc::Rgb{static_cast<std::uint8_t>(k[0] >> 1), static_cast<std::uint8_t>(k[1] >> 1),
                     static_cast<std::uint8_t>((k[2] >> 1) * 37)};
}

}  // namespace

TEST_CASE("octomap_tree.ColorOcTree .ot: liboctomap reads every voxel's value and colour") {
  for (std::uint64_t seed : {1u, 2u}) {
    CAPTURE(seed);
    const OccupancyMap<OcKey> map = mixed_map(seed);
    const std::string path = tree_file("colors.ot");
    io::write_color_ot(path, map, test_color);
    std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(path));
    auto* t = dynamic_cast<octomap::ColorOcTree*>(read.get());
    REQUIRE(t != nullptr);
    std::size_t finest = 0, wrong_value = 0, wrong_color = 0, colored = 0;
    knnocc::test::for_each_octomap_voxel(*t, [&](const OcKey& k,
                                                 const octomap::ColorOcTreeNode& leaf) {
      ++finest;
      const auto v = map.logodds(k);
      wrong_value += !v || *v != leaf.getLogOdds();
      const auto expect = v && map.is_occupied(*v) ? test_color(k) : std::nullopt;
      const auto c = leaf.getColor();
      colored += leaf.isColorSet();
      wrong_color += c != (expect ? octomap::ColorOcTreeNode::Color(expect->r, expect->g, expect->b)
                                  : octomap::ColorOcTreeNode::Color());
    });
    CHECK(finest == map.num_voxels());
    CHECK(wrong_value == 0);
    CHECK(wrong_color == 0);
    CHECK(colored > 1000);
    // Inner nodes hold ColorOcTree's own rule: updateInnerOccupancy() (max of the children's
    // values, mean of their colours) changes nothing.
    std::vector<std::pair<float, octomap::ColorOcTreeNode::Color>> inner;
    for (auto it = t->begin_tree(), end = t->end_tree(); it != end; ++it)
      if (!it.isLeaf()) inner.emplace_back(it->getLogOdds(), it->getColor());
    t->updateInnerOccupancy();
    std::size_t i = 0, changed = 0;
    for (auto it = t->begin_tree(), end = t->end_tree(); it != end; ++it)
      if (!it.isLeaf()) changed += inner[i++] != std::make_pair(it->getLogOdds(), it->getColor());
    CHECK(i == inner.size());
    CHECK(changed == 0);
    // Without colours the file is what liboctomap writes for a ColorOcTree of the same values.
    octomap::ColorOcTree plain(0.05);
    map.for_each_voxel([&](const OcKey& k, float v) {
      plain.setNodeValue(octomap::OcTreeKey(k[0], k[1], k[2]), v);
    });
    std::ostringstream bytes;
    plain.write(bytes);
    CHECK(io::encode_color_ot(map, [](const OcKey&) { return std::nullopt; }) == bytes.str());
  }
}

TEST_CASE("octomap_tree.read_octree_colors: a written ColorOcTree's colours read back exactly") {
  const OccupancyMap<OcKey> map = mixed_map(3);
  const std::string path = tree_file("colors_back.ot");
  io::write_color_ot(path, map, test_color);
  io::OctreeColors colors;
  const OccupancyMap<OcKey> back = io::read_octree_colors(path, {}, colors);
  CHECK(colors.color_tree);
  CHECK(colors.free_colored_voxels == 0);
  std::size_t expected = 0, wrong = 0;
  map.for_each_voxel([&](const OcKey& k, float v) {
    const auto c = test_color(k);
    if (map.is_occupied(v) && c && *c != knnocc::Rgb{255, 255, 255}) ++expected;
  });
  for (const auto& [k, c] : colors.voxels) {
    const auto v = map.logodds(k);
    wrong += !v || !map.is_occupied(*v) || test_color(k) != c;
  }
  CHECK(expected > 1000);
  CHECK(colors.voxels.size() == expected);
  CHECK(wrong == 0);
  // Written again from what was read: the same bytes.
  std::map<std::uint64_t, knnocc::Rgb> by_key;
  for (const auto& [k, c] : colors.voxels) by_key[k.pack()] = c;
  CHECK(io::encode_color_ot(back, [&](const OcKey& k) -> std::optional<knnocc::Rgb> {
          const auto it = by_key.find(k.pack());
          if (it == by_key.end()) return std::nullopt;
          return it->second;
        }) == io::encode_color_ot(map, test_color));
  // A plain OcTree and a .bt have no colours.
  io::write_ot(path, map);
  io::read_octree_colors(path, {}, colors);
  CHECK(!colors.color_tree);
  CHECK(colors.voxels.empty());
}

TEST_CASE("octomap_tree.read_octree_colors: liboctomap's pruned and free coloured leaves") {
  octomap::ColorOcTree color(0.1);
  // Eight occupied siblings of one colour, pruned by liboctomap into one leaf at depth 15.
  for (int i = 0; i < 8; ++i) {
    const octomap::OcTreeKey k(1000 + (i & 1), 2000 + ((i >> 1) & 1), 3000 + ((i >> 2) & 1));
    color.updateNode(k, true);
    color.updateNode(k, true);
    color.setNodeColor(k, 10, 20, 30);
  }
  color.prune();
  // One free voxel with a colour; one occupied voxel without (white).
  color.updateNode(octomap::OcTreeKey(500, 500, 500), false);
  color.setNodeColor(octomap::OcTreeKey(500, 500, 500), 1, 2, 3);
  color.updateNode(octomap::OcTreeKey(600, 600, 600), true);
  const std::string path = tree_file("color_pruned.ot");
  REQUIRE(color.write(path));
  io::OctreeColors colors;
  const auto map = io::read_octree_colors(path, {}, colors);
  CHECK(colors.color_tree);
  CHECK(colors.free_colored_voxels == 1);
  REQUIRE(colors.voxels.size() == 8);
  for (const auto& [k, c] : colors.voxels) {
    CHECK(c == knnocc::Rgb{10, 20, 30});
    CHECK(map.is_occupied(*map.logodds(k)));
  }
}

TEST_CASE("octomap_tree.reads liboctomap's ColorOcTree and OcTreeStamped files") {
  octomap::ColorOcTree color(0.1);
  knnocc::test::Rng rng(5);
  std::uniform_real_distribution<float> u(-2.f, 2.f);
  for (int i = 0; i < 500; ++i) {
    const octomap::point3d p(u(rng), u(rng), u(rng));
    color.updateNode(p, i % 3 != 0);
    color.setNodeColor(color.coordToKey(p), 10, 20, 30);
  }
  const std::string path = tree_file("color.ot");
  REQUIRE(color.write(path));
  const auto map = io::read_octree(path);
  std::size_t leaves = 0, wrong = 0;
  for (auto it = color.begin_leafs(), end = color.end_leafs(); it != end; ++it) {
    ++leaves;
    const auto v =
        map.logodds_at_depth(OcKey(it.getIndexKey()[0], it.getIndexKey()[1], it.getIndexKey()[2]),
                             static_cast<int>(it.getDepth()));
    wrong += !v || *v != it->getLogOdds();
  }
  CHECK(leaves > 100);
  CHECK(wrong == 0);

  octomap::OcTreeStamped stamped(0.1);
  for (int i = 0; i < 300; ++i) stamped.updateNode(octomap::point3d(u(rng), u(rng), u(rng)), true);
  const std::string spath = tree_file("stamped.ot");
  REQUIRE(stamped.write(spath));
  CHECK(io::read_octree(spath).num_voxels() == stamped.getNumLeafNodes());
}
#endif

TEST_CASE("octomap_tree.memory_limit refuses a file whose leaves surely do not fit") {
  // Two free leaves at depth 6 (2^30 voxels each): 71 bytes that expand to 2^31 voxels, within
  // max_voxels; as compacted bricks they take 4 M brick records (hundreds of MB).
  const std::string bytes = std::string(io::detail::kBtFirstLine) +
                            "\nid OcTree\nsize 8\nres 0.1\ndata\n" +
                            std::string("\x03\x00\x03\x00\x03\x00\x03\x00\x03\x00\x05\x00", 12);
  const std::string path = tree_file("two_giant_leaves.bt");
  write_file(path, bytes);
  const io::OctreeInfo info = io::inspect_octree(path);
  CHECK(info.free_voxels == (std::uint64_t{1} << 31));
  io::OctreeReadOptions o;
  o.memory_limit = std::size_t{64} << 20;
  try {
    (void)io::read_octree(path, o);
    FAIL("no error");
  } catch (const io::Error& e) {
    CHECK(e.file() == path);
    CHECK_MESSAGE(e.problem().find("voxels need at least") != std::string::npos, e.problem());
    CHECK(e.problem().find("memory limit of 67 MB") != std::string::npos);
  }
  // A small map reads under a small limit, unchanged.
  const OccupancyMap<OcKey> map = mixed_map(3);
  const std::string small = tree_file("small_limited.bt");
  io::write_bt(small, map);
  o.memory_limit = 4 * map.memory_usage() + (std::size_t{1} << 20);
  CHECK(io::encode_bt(io::read_octree(small, o)) == io::encode_bt(map));
}

TEST_CASE("octree: a node encoded apart is the whole file's; counting a .bt node is encoding it") {
  // Bricks whole and partly known, uniform and mixed, around value ties at the threshold, so
  // every pruning case occurs: encode_node(0) is encode()'s node stream, the nodes of every depth
  // are the whole tree's, and the .bt count from masks (bytes = false) equals the encoding.
  std::mt19937 rng(29);
  std::uniform_int_distribution<int> cell(32700, 32840), pick(0, 9);
  OccupancyMap<OcKey> map(0.1);
  for (int i = 0; i < 60000; ++i) {
    const OcKey k(static_cast<std::uint16_t>(cell(rng)), static_cast<std::uint16_t>(cell(rng)),
                  static_cast<std::uint16_t>(cell(rng) / 4 + 24560));
    const int p = pick(rng);
    map.set(k, p < 4 ? -1.0f : p < 8 ? 1.5f : p == 8 ? 0.0f : -0.25f);
  }
  for (int x = 32768; x < 32800; ++x)  // whole uniform bricks and uniform 2x2x2 blocks
    for (int y = 32768; y < 32784; ++y)
      for (int z = 32768; z < 32776; ++z)
        map.set(OcKey(static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y),
                      static_cast<std::uint16_t>(z)),
                x < 32784 ? -2.0f
                : (z & 2) ? 3.5f
                          : 1.0f);
  io::detail::OctreeEncoder<false> bt(map, "");
  io::detail::OctreeEncoder<true> ot(map, "");
  const std::string whole_bt = io::encode_bt(map), whole_ot = io::encode_ot(map);
  const io::detail::OctreeNode root_bt = bt.encode_node(0, {0, 0, 0});
  const io::detail::OctreeNode root_ot = ot.encode_node(0, {0, 0, 0});
  CHECK(whole_bt == bt.header(root_bt.nodes) + root_bt.data);
  CHECK(whole_ot == ot.header(root_ot.nodes) + root_ot.data);
  std::size_t nodes = 0, leaves = 0;
  for (const int d : {1, 5, 9, 11, 12, 13}) {
    const std::uint32_t span = 1u << (16 - d);
    for (std::uint32_t x = 32768 - 4 * span; x < 32768 + 4 * span; x += span)
      for (std::uint32_t y = 32768 - 4 * span; y < 32768 + 4 * span; y += span)
        for (std::uint32_t z = 32768 - 4 * span; z < 32768 + 4 * span; z += span) {
          if (x > 65535 || y > 65535 || z > 65535) continue;
          const std::array<std::uint32_t, 3> corner{x, y, z};
          const io::detail::OctreeNode a = bt.encode_node(d, corner);
          const io::detail::OctreeNode b = bt.encode_node(d, corner, false);
          CHECK(a.present == b.present);
          CHECK(a.nodes == b.nodes);
          CHECK(a.summary.leaf == b.summary.leaf);
          CHECK(std::memcmp(&a.summary.value, &b.summary.value, sizeof(float)) == 0);
          CHECK(b.data.empty());
          nodes += a.nodes;
          leaves += a.present && a.summary.leaf;
        }
  }
  CHECK(nodes > 10000);
  CHECK(leaves >= 4);  // collapsed nodes at some depth
}
