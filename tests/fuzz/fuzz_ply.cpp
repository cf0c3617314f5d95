// PLY reader (ascii, binary little/big endian, any properties).
#include <knnocc/io/ply.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".ply", [](const std::string& p) {
    const knnocc::io::Cloud c = knnocc::io::read_ply(p);
    if (!c.ids.empty() && c.ids.size() != c.points.size()) std::abort();
  });
  return 0;
}
