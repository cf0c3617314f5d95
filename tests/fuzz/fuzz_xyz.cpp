// ASCII x y z reader.
#include <knnocc/io/xyz.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".xyz",
                                       [](const std::string& p) { knnocc::io::read_xyz(p); });
  return 0;
}
