// Reference-shape reader of `knnocc eval`, and the metrics on what it accepts.
#include <knnocc/eval/reference.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".txt", [](const std::string& p) {
    const knnocc::eval::Reference ref = knnocc::eval::read_reference(p);
    const double d = ref.distance({0.1, 0.2, 0.3});
    if (!(d >= 0)) std::abort();  // +inf is fine (far away), NaN is not
    ref.relation({0, 0, 0}, {0.1, 0.1, 0.1});
  });
  return 0;
}
