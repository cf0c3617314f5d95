#pragma once
// knnocc_alloc_tests replaces the global operator new (counting_new.cpp) to count allocations and
// record the largest single request. It lives in a binary of its own so that the rest of the
// suite runs on the standard allocator.
#include <cstddef>

namespace knnocc::test {

/// operator-new calls since the program started.
std::size_t allocations();
/// Largest single operator-new request since the last reset: lets the reader tests check that a
/// lying header is never believed.
std::size_t largest_allocation();
void reset_largest_allocation();

/// Bytes held through operator new right now, and the most held since the last reset (glibc:
/// malloc_usable_size; elsewhere both stay 0 and the tests that need them skip).
std::size_t live_bytes();
std::size_t peak_live_bytes();
void reset_peak_live_bytes();
bool tracks_live_bytes();

}  // namespace knnocc::test
