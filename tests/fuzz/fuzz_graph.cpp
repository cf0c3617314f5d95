// OctoMap ScanGraph (.graph) reader.
#include <knnocc/io/scan_graph.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".graph", [](const std::string& p) {
    for (const auto& node : knnocc::io::read_scan_graph(p).nodes)
      if (!node.pose.t.allFinite()) std::abort();
  });
  return 0;
}
