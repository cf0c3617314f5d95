// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// MemoryLimitError: what a map reports when a write would take it past its memory limit
// (OccupancyMap::set_memory_limit). A std::bad_alloc, so code that already handles allocation
// failure handles it too; what() says the limit and what the write needed. Without exceptions the
// message is printed and the program aborts.

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <new>

#include "config.hpp"

namespace knnocc {

class MemoryLimitError : public std::bad_alloc {
 public:
  MemoryLimitError(std::size_t limit, std::size_t needed) : limit_(limit), needed_(needed) {
    std::snprintf(what_, sizeof what_,
                  "map memory limit of %.1f MB reached: the write needs %.1f MB in all",
                  static_cast<double>(limit) / 1e6, static_cast<double>(needed) / 1e6);
  }
  const char* what() const noexcept override { return what_; }
  /// The limit (bytes) and the memory_usage() the refused write would have led to.
  std::size_t limit() const noexcept { return limit_; }
  std::size_t needed() const noexcept { return needed_; }

 private:
  std::size_t limit_, needed_;
  char what_[128];  // no allocation while reporting a memory problem
};

namespace detail {
[[noreturn]] inline void memory_limit_exceeded(std::size_t limit, std::size_t needed) {
#if KNNOCC_HAS_EXCEPTIONS
  throw MemoryLimitError(limit, needed);
#else
  std::fprintf(stderr, "knnocc: %s\n", MemoryLimitError(limit, needed).what());
  std::abort();
#endif
}
}  // namespace detail

}  // namespace knnocc
