// Voxel list reader (x y z logodds per line).
#include <knnocc/io/voxel_list.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(
      data, size, ".txt", [](const std::string& p) { knnocc::io::read_voxel_list(p); });
  return 0;
}
