// Writes the fuzzers' seed corpora (generated at build time, never committed): one folder per
// fuzzer under the given directory, with valid files of each format and variant.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <knnocc/eval/reference.hpp>
#include <knnocc/io/kitti.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/scan_graph.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/io/voxel_list.hpp>

namespace fs = std::filesystem;

namespace {

void text(const fs::path& p, const std::string& content) {
  std::ofstream(p, std::ios::binary) << content;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: knnocc_fuzz_seeds DIR\n");
    return 2;
  }
  const fs::path root(argv[1]);
  for (const char* d : {"ply", "xyz", "poses", "voxel_list", "reference", "tracker", "pcd", "lzf",
                        "octree", "graph", "kitti"})
    fs::create_directories(root / d);
  using knnocc::Point3f;
  const std::vector<Point3f> pts = {{1, 2, 3}, {-1.5f, 0.25f, 8}, {0, 0, 0}, {1e-3f, -7, 2}};
  const std::vector<std::uint64_t> ids = {7, 8, 4000000000u, 0};
  knnocc::io::write_ply((root / "ply" / "binary.ply").string(), pts);
  knnocc::io::write_ply((root / "ply" / "binary_ids.ply").string(), pts, &ids);
  knnocc::io::write_ply((root / "ply" / "ascii_ids.ply").string(), pts, &ids, false);
  text(root / "ply" / "big_endian_double.ply",
       std::string("ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty double x\n"
                   "property double y\nproperty double z\nproperty uchar red\nend_header\n") +
           std::string("\x3f\xf0\0\0\0\0\0\0\x40\0\0\0\0\0\0\0\x40\x08\0\0\0\0\0\0\xff", 25));
  text(root / "ply" / "faces.ply",
       "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\n"
       "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
       "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  text(root / "xyz" / "points.xyz", "1 2 3\n-4.5 6e-3 7 # comment\n\n8 9 10\n");
  text(root / "poses" / "poses.txt",
       "# stamp tx ty tz qx qy qz qw\n0 1 2 3 0 0 0 1\n1.5 -1 0 2 0.7071068 0 0 0.7071068\n");
  knnocc::io::write_voxel_list((root / "voxel_list" / "voxels.txt").string(),
                               {{0.05, 0.05, 0.05, 0.85f}, {-1.25, 2.35, 0.15, -0.4f}});
  knnocc::eval::Reference ref;
  ref.has_ground = true;
  ref.ellipsoids.push_back({{0, 0, 1.6}, {0.9, 0.9, 0.7}});
  ref.cuboids.push_back({{-0.27, -0.27, 0}, {0.27, 0.27, 0.77}});
  knnocc::eval::write_reference((root / "reference" / "reference.txt").string(), ref);
  std::string ops = "\x03";  // k = 4
  for (int i = 0; i < 60; ++i) ops += static_cast<char>((i * 37 + 11) & 0xff);
  text(root / "tracker" / "ops.bin", ops);
  using knnocc::io::PcdData;
  knnocc::io::write_pcd((root / "pcd" / "ascii.pcd").string(), pts, &ids, PcdData::ascii);
  knnocc::io::write_pcd((root / "pcd" / "binary.pcd").string(), pts, nullptr, PcdData::binary);
  std::vector<Point3f> many;
  for (int i = 0; i < 300; ++i) many.push_back({0.1f * (i % 10), 0.2f * (i / 10), 1.0f});
  knnocc::io::write_pcd((root / "pcd" / "compressed.pcd").string(), many, nullptr,
                        PcdData::binary_compressed);
  text(root / "lzf" / "text.bin",
       std::string("\x01\x00", 2) + "aaaaaaaaaaaaaaaabcabcabcabcabc the quick brown fox");
  knnocc::OccupancyMap<knnocc::OcKey> map(0.1);
  for (int i = 0; i < 64; ++i) {  // one full 2x2x2 block (pruned in the file) and scattered voxels
    knnocc::OcKey k;
    if (map.grid().coord_to_key(0.05 + 0.1 * (i % 2), 0.05 + 0.1 * ((i / 2) % 2),
                                0.05 + 0.1 * ((i / 4) % 2), k) &&
        i < 8)
      map.set(k, 2.0f);
    if (map.grid().coord_to_key(0.3 * i - 5, 0.7 * (i % 7), -0.2 * i, k))
      map.set(k, i % 3 ? -1.0f : 1.5f);
  }
  knnocc::io::write_bt((root / "octree" / "map.bt").string(), map);
  knnocc::io::write_ot((root / "octree" / "map.ot").string(), map);
  knnocc::io::ScanGraph graph;
  for (std::uint32_t n = 0; n < 2; ++n) {
    knnocc::io::ScanNode node;
    node.id = n;
    node.pose.t = Eigen::Vector3d(n, 0.5, 0);
    node.points = pts;
    graph.nodes.push_back(node);
  }
  graph.edges.push_back({0, 1, knnocc::io::Pose{}});
  knnocc::io::write_scan_graph((root / "graph" / "two.graph").string(), graph);
  knnocc::io::write_kitti_bin((root / "kitti" / "scan.bin").string(), pts);
  text(root / "kitti" / "calib.txt",
       "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr: 0 -1 0 0.1 0 0 -1 0.2 1 0 0 -0.3\n");
  text(root / "kitti" / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1.5 0 1 0 0 0 0 1 0.2\n");
  text(root / "kitti" / "tum.txt", "0 1 2 3 0 0 0 1\n");
  std::printf("seeds written to %s\n", root.string().c_str());
  return 0;
}
