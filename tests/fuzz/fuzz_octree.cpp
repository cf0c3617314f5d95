// OctoMap .bt/.ot reader; what it accepts is written back as .ot and read again unchanged.
#include <knnocc/io/octomap_tree.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".ot", [](const std::string& p) {
    knnocc::io::OctreeReadOptions options;
    options.max_voxels = std::uint64_t{1} << 24;  // keep expansions quick under the fuzzer
    const auto map = knnocc::io::read_octree(p, options);
    const std::string again = p + ".again.ot";
    knnocc::io::write_ot(again, map);
    const auto back = knnocc::io::read_octree(again);
    if (back.num_voxels() != map.num_voxels()) std::abort();
    std::size_t differ = 0;
    map.for_each_voxel([&](const knnocc::OcKey& k, float v) {
      const auto w = back.logodds(k);
      differ += !w || *w != v;
    });
    if (differ) std::abort();
  });
  return 0;
}
