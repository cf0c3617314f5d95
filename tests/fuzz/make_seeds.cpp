// Writes the fuzzers' seed corpora (generated at build time, never committed): one folder per
// fuzzer under the given directory, with valid files of each format and variant.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <knnocc/eval/reference.hpp>
#include <knnocc/io/ply.hpp>
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
  for (const char* d : {"ply", "xyz", "poses", "voxel_list", "reference", "tracker"})
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
  std::printf("seeds written to %s\n", root.string().c_str());
  return 0;
}
