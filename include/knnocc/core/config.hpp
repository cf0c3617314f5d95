// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Build configuration shared by every knnocc header.
//
// The core headers (keys, map, ray casting, sensor models) work with -fno-exceptions: invalid
// arguments then print one line to stderr and abort instead of throwing std::invalid_argument.

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#if defined(__cpp_exceptions) || defined(__EXCEPTIONS) || defined(_CPPUNWIND)
#define KNNOCC_HAS_EXCEPTIONS 1
#else
#define KNNOCC_HAS_EXCEPTIONS 0
#endif

// Inlining where the hot loops need it to be certain (per-point and per-step helpers) and where
// it must not happen (rare paths kept out of a loop, code that must keep the caller's flags).
#if defined(__GNUC__) || defined(__clang__)
#define KNNOCC_ALWAYS_INLINE __attribute__((always_inline)) inline
#define KNNOCC_NOINLINE __attribute__((noinline))
#else
#define KNNOCC_ALWAYS_INLINE inline
#define KNNOCC_NOINLINE
#endif

namespace knnocc::detail {

/// Reports a caller error: std::invalid_argument, or a message and abort() without exceptions.
[[noreturn]] inline void invalid_argument(const std::string& what) {
#if KNNOCC_HAS_EXCEPTIONS
  throw std::invalid_argument(what);
#else
  std::fprintf(stderr, "knnocc: %s\n", what.c_str());
  std::abort();
#endif
}

}  // namespace knnocc::detail
