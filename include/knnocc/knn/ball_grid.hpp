// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// BallGrid: which k-NN balls may contain a point.
//
// Inserting p changes q's k-NN iff p lies in q's k-NN ball (centre q, radius d_k(q)), ties
// decided by id. BallGrid answers "which balls may contain p" without a search radius: ball
// (c, r) is registered at the level whose cells are at least 2r wide, in the (at most 8) cells
// its bounding box touches; a query looks up the one cell holding p on each level in use. Every
// ball that contains p is returned (plus some that do not; callers test exactly), so sparse
// points with huge balls cost as little as dense ones with small balls. Balls of unbounded
// radius (points with fewer than k neighbours) sit in a list returned by every query.
//
// Cells are hashed by (level, x, y, z) folded into 64 bits; folding may merge far-apart cells,
// which only adds candidates.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../core/detail/flat_index.hpp"
#include "../core/point3.hpp"

namespace knnocc::detail {

class BallGrid {
 public:
  using index_type = std::uint32_t;

  /// Registers ball (c, r) for index i; r = +inf means "contains every point".
  void insert(index_type i, const Point3d& c, double r) {
    visit(c, r, [&](auto& v) { v.push_back(i); });
  }

  /// Unregisters a ball given with exactly the arguments it was inserted with.
  void erase(index_type i, const Point3d& c, double r) {
    visit(c, r, [&](std::vector<index_type>& v) {
      for (std::size_t j = 0; j < v.size(); ++j)
        if (v[j] == i) {
          v[j] = v.back();
          v.pop_back();
          return;
        }
    });
  }

  /// Appends every index whose ball may contain p (a superset; may repeat an index).
  void candidates(const Point3d& p, std::vector<index_type>& out) const {
    out.insert(out.end(), unbounded_.begin(), unbounded_.end());
    for (int l = 0; l < kLevels; ++l) {
      if (level_count_[l] == 0) continue;
      const double size = cell_size(l);
      const std::uint32_t slot =
          index_.find(key(l, cell(p.x, size), cell(p.y, size), cell(p.z, size)));
      if (slot != FlatIndex::kNone) out.insert(out.end(), cells_[slot].begin(), cells_[slot].end());
    }
  }

  void clear() {
    cells_.clear();
    index_.reset();
    unbounded_.clear();
    for (auto& n : level_count_) n = 0;
  }

  std::size_t memory_usage() const {
    std::size_t bytes = unbounded_.capacity() * sizeof(index_type);
    for (const auto& v : cells_) bytes += sizeof(v) + v.capacity() * sizeof(index_type);
    return bytes + index_.memory_usage();
  }

 private:
  static constexpr int kLevels = 48;
  static constexpr double kFinest = 1.0 / (1 << 20);  // ~1 um; level l cells are kFinest * 2^l

  static double cell_size(int l) { return std::ldexp(kFinest, l); }
  static std::int64_t cell(double x, double size) {
    // Clamped, so huge coordinates cannot overflow the cast; clamping keeps the order of cells,
    // which is all correctness needs.
    const double f = std::floor(x / size);
    return static_cast<std::int64_t>(std::min(std::max(f, -4e18), 4e18));
  }
  static std::uint64_t key(int l, std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::uint64_t m = (std::uint64_t{1} << 19) - 1;
    return static_cast<std::uint64_t>(l) | ((static_cast<std::uint64_t>(x) & m) << 6) |
           ((static_cast<std::uint64_t>(y) & m) << 25) |
           ((static_cast<std::uint64_t>(z) & m) << 44);
  }

  // Calls f(vector) for every cell list ball (c, r) belongs to.
  template <class F>
  void visit(const Point3d& c, double r, F&& f) {
    // Grow the box a little so rounding in c +- r can never leave out the cell of a point that
    // dist2() puts inside the ball.
    const double margin = 1e-9 * (r + std::fabs(c.x) + std::fabs(c.y) + std::fabs(c.z)) + 1e-300;
    const double reach = r + margin;
    int l = 0;
    while (l < kLevels && cell_size(l) < 2.0 * reach) ++l;
    if (!std::isfinite(reach) || l == kLevels) {
      f(unbounded_);
      return;
    }
    const double size = cell_size(l);
    for (std::int64_t x = cell(c.x - reach, size); x <= cell(c.x + reach, size); ++x)
      for (std::int64_t y = cell(c.y - reach, size); y <= cell(c.y + reach, size); ++y)
        for (std::int64_t z = cell(c.z - reach, size); z <= cell(c.z + reach, size); ++z) {
          bool inserted = false;
          const auto next = static_cast<std::uint32_t>(cells_.size());
          const std::uint32_t slot = index_.find_or_insert(key(l, x, y, z), next, inserted);
          if (inserted) cells_.emplace_back();
          std::vector<index_type>& v = cells_[slot];
          const std::size_t before = v.size();
          f(v);
          level_count_[l] += v.size();
          level_count_[l] -= before;
        }
  }

  // Cell key -> slot in cells_. Cells are never dropped (a cell that empties is usually refilled
  // soon); clear() releases everything.
  FlatIndex index_;
  std::vector<std::vector<index_type>> cells_;
  std::vector<index_type> unbounded_;
  std::size_t level_count_[kLevels] = {};
};

}  // namespace knnocc::detail
