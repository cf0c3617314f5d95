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
