// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The rays of a collected scan (every thread's ScanPart) handed out in chunks, to whichever thread
// asks next (ScanInserter, phase 2): small chunks balance the threads, since rays differ in length.

#include <algorithm>
#include <cstddef>
#include <vector>

#include "thread_scratch.hpp"
#include "work_queue.hpp"

namespace knnocc::detail {

class RayChunks {
 public:
  /// The rays of the first `threads` scratches' parts, `rays` in all; `first_chunk` is scratch
  /// (kept by the caller for its memory).
  RayChunks(const ThreadScratches& scratch, unsigned threads, std::size_t rays,
            std::vector<std::size_t>& first_chunk)
      : scratch_(scratch),
        chunk_(std::max<std::size_t>(256, std::min<std::size_t>(4096, rays / 64 + 1))),
        first_chunk_(first_chunk),
        queue_(plan(scratch, threads, chunk_, first_chunk)) {}

  /// The next chunk of rays, [first, last); false when every chunk is taken.
  bool take(const RayEnd*& first, const RayEnd*& last) {
    std::size_t c;
    if (!queue_.take(c)) return false;
    unsigned t = 0;
    while (c >= first_chunk_[t + 1]) ++t;
    const auto& rays = scratch_[t]->part.rays;
    const std::size_t begin = (c - first_chunk_[t]) * chunk_;
    first = rays.data() + begin;
    last = rays.data() + std::min(rays.size(), begin + chunk_);
    return true;
  }

 private:
  // first_chunk[t]: the first chunk of part t (prefix sums); returns the number of chunks.
  static std::size_t plan(const ThreadScratches& scratch, unsigned threads, std::size_t chunk,
                          std::vector<std::size_t>& first_chunk) {
    first_chunk.resize(threads + 1);
    first_chunk[0] = 0;
    for (unsigned t = 0; t < threads; ++t)
      first_chunk[t + 1] = first_chunk[t] + (scratch[t]->part.rays.size() + chunk - 1) / chunk;
    return first_chunk[threads];
  }

  const ThreadScratches& scratch_;
  std::size_t chunk_;  // rays per chunk
  const std::vector<std::size_t>& first_chunk_;
  WorkQueue queue_;
};

}  // namespace knnocc::detail
