// Reference-shape reader of `knnocc eval`, and the metrics on what it accepts.
#include <cstdint>
#include <stdexcept>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/eval/reference.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".txt", [](const std::string& p) {
    const knnocc::eval::Reference ref = knnocc::eval::read_reference(p);
    const double d = ref.distance({0.1, 0.2, 0.3});
    if (!(d >= 0)) std::abort();  // +inf is fine (far away), NaN is not
    ref.relation({0, 0, 0}, {0.1, 0.1, 0.1});
    // The metrics on an empty map at a coarse grid: the shell count walks the reference's box,
    // at most 2^20 voxels here (about a second under the sanitizers; libFuzzer's timeout is 10 s).
    try {
      const knnocc::OccupancyMap<knnocc::OcKey> map(5.0);
      knnocc::eval::MetricOptions opt;
      opt.max_shell_box = std::uint64_t{1} << 20;
      knnocc::eval::evaluate(map, ref, opt);
    } catch (const std::invalid_argument&) {  // a box too large to walk: the documented refusal
    }
  });
  return 0;
}
