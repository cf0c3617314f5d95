// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RayBlock: up to 256 LinearRays set up field by field (a structure of arrays: the AVX-512 walk
// loads one field of eight rays in one instruction), and BlockRays, a block read as a ray stream.

#include <cstddef>
#include <cstdint>
#include <limits>

#include "linear_ray.hpp"

namespace knnocc::detail {

/// Up to kRays rays set up for the walks, field by field (a structure of arrays, so that the
/// AVX-512 walk loads one field of eight rays in one instruction). Entries from size up to the
/// next multiple of kBundle are parked rays: they stand on the first ray's start voxel and never
/// step.
struct RayBlock {
  static constexpr std::size_t kRays = 256;
  static constexpr std::size_t kBundle = 16;  // rays the AVX-512 walk takes at once

  alignas(64) double t_max[3][kRays];
  alignas(64) double t_delta[3][kRays];
  alignas(64) std::int64_t stride[3][kRays];
  alignas(64) std::int64_t index[kRays];       // start voxel
  alignas(64) std::int64_t lane_steps[kRays];  // steps with no end test (lane_steps_of)
  double length[kRays];
  std::int64_t end_index[kRays];
  std::int64_t steps_to_end[kRays];
  bool clear_end[kRays];
  std::size_t size = 0;

  /// The steps a ray takes before any end test: for a clear end, all but the step onto the end
  /// voxel (so the ray's voxels are walked, and nothing more); else its unchecked steps, and the
  /// scalar walk goes on from there.
  static std::int64_t lane_steps_of(std::int64_t steps_to_end, bool clear_end) {
    return clear_end ? steps_to_end - 1 : unchecked_steps(steps_to_end);
  }

  void set(std::size_t i, const LinearRay& r) {
    for (int a = 0; a < 3; ++a) {
      t_max[a][i] = r.state.t_max[a];
      t_delta[a][i] = r.state.t_delta[a];
      stride[a][i] = r.stride[a];
    }
    index[i] = r.index;
    length[i] = r.state.length;
    end_index[i] = r.end_index;
    steps_to_end[i] = r.state.steps_to_end;
    clear_end[i] = r.clear_end;
    lane_steps[i] = lane_steps_of(r.state.steps_to_end, r.clear_end);
  }
  LinearRay get(std::size_t i) const {
    LinearRay r;
    for (int a = 0; a < 3; ++a) {
      r.state.t_max[a] = t_max[a][i];
      r.state.t_delta[a] = t_delta[a][i];
      r.stride[a] = stride[a][i];
    }
    r.index = index[i];
    r.state.length = length[i];
    r.end_index = end_index[i];
    r.state.steps_to_end = steps_to_end[i];
    r.clear_end = clear_end[i];
    return r;
  }
  /// Sets size = n (1 <= n <= kRays, rays 0 .. n - 1 set) and parks the rest of the last bundle.
  void close(std::size_t n) {
    size = n;
    for (std::size_t i = n; i % kBundle != 0; ++i) {
      for (int a = 0; a < 3; ++a) {
        t_max[a][i] = std::numeric_limits<double>::infinity();
        t_delta[a][i] = 0.0;
        stride[a][i] = 0;
      }
      index[i] = end_index[i] = index[0];
      length[i] = 0.0;
      steps_to_end[i] = lane_steps[i] = 0;
      clear_end[i] = true;
    }
  }
};

/// A RayBlock's rays as a ray stream (for the four-lane and scalar walks).
class BlockRays {
 public:
  explicit BlockRays(const RayBlock& block) : block_(block) {}
  const LinearRay* operator()() {
    if (next_ == block_.size) return nullptr;
    ray_ = block_.get(next_++);
    return &ray_;
  }

 private:
  const RayBlock& block_;
  std::size_t next_ = 0;
  LinearRay ray_;
};

}  // namespace knnocc::detail
