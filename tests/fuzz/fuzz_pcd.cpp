// PCD reader (ascii, binary, binary_compressed with LZF; v0.5-0.7 headers).
#include <knnocc/io/pcd.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".pcd", [](const std::string& p) {
    const knnocc::io::Cloud c = knnocc::io::read_pcd(p);
    if (!c.ids.empty() && c.ids.size() != c.points.size()) std::abort();
  });
  return 0;
}
