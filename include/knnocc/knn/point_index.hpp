// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PointIndex: the map point cloud with stable 64-bit ids, searched with nanoflann.
//
// The dataset is append-only: a point added (or moved) gets a new dataset index, a removed index
// is only marked dead (nanoflann's lazy removePoint in the dynamic tree, a flag the collectors
// check in the static one) and never reused, and compact() rebuilds dataset and trees from the
// live points when dead entries pile up. Two trees: a static KD-tree over the bulk (rebuilt when
// the recent points outgrow a quarter of it) and nanoflann's dynamic KD-tree
// (KDTreeSingleIndexDynamicAdaptor) over the points added since.
//
// Neighbour order is (squared distance, id): ties are broken by the smaller id, so every k-NN
// set is unique and equals the brute-force one. Squared distances come from one function,
// dist2(), used by the tree search (as its metric) and by any oracle alike.
//
// Thread safety: const queries may run concurrently while nothing is added, removed or compacted.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <unordered_map>
#include <vector>

#include "../core/config.hpp"
#include "../core/point3.hpp"
#include "nanoflann_compat.hpp"

namespace knnocc {

/// Squared Euclidean distance; the single definition used for every neighbour decision.
inline double dist2(const Point3d& a, const Point3d& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return dx * dx + dy * dy + dz * dz;
}

/// One neighbour: dataset index, id and squared distance.
struct Neighbor {
  std::uint32_t index = 0;
  std::uint64_t id = 0;
  double d2 = 0.0;
};

/// (d2, id) order: the total order that defines k-NN sets.
inline bool closer(double d2a, std::uint64_t ida, double d2b, std::uint64_t idb) {
  return d2a < d2b || (d2a == d2b && ida < idb);
}

namespace detail {

// nanoflann's view of a slice [first, first + count) of the dataset, in local indices.
struct PointCloudAdaptor {
  const std::vector<Point3d>* pts = nullptr;
  std::size_t first = 0, count = 0;
  std::size_t kdtree_get_point_count() const { return count; }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const {
    const Point3d& p = (*pts)[first + i];
    return dim == 0 ? p.x : (dim == 1 ? p.y : p.z);
  }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const {
    return false;
  }
};

// The trees' metric is dist2() itself, so the trees and brute force agree to the last bit.
struct Dist2Metric {
  using ElementType = double;
  using DistanceType = double;
  const PointCloudAdaptor& data;
  explicit Dist2Metric(const PointCloudAdaptor& d) : data(d) {}
  template <class I>
  double evalMetric(const double* a, I b, std::size_t) const {
    return dist2(Point3d{a[0], a[1], a[2]}, (*data.pts)[data.first + static_cast<std::size_t>(b)]);
  }
  template <class U, class V>
  double accum_dist(const U a, const V b, std::size_t) const {
    return (a - b) * (a - b);
  }
};

// nanoflann only offers a point to the result set when dist < worstDist(), and its pruning bound
// for a subtree (built up incrementally from per-axis terms) can exceed the true distance by a
// few ulps. Reporting a slightly larger worst distance lets every point at exactly the worst
// distance through, so ties are decided by id here; the extra candidates are few and are tested
// exactly by the collectors.
inline double admit_equal(double d2) {
  return d2 + d2 * 1e-13 + std::numeric_limits<double>::denorm_min();
}

// The k nearest by (d2, id), skipping one index (the query point itself).
class KnnCollector {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;

  KnnCollector(std::size_t k, std::uint32_t skip, const std::vector<std::uint64_t>& ids,
               const std::vector<std::uint8_t>& alive, std::vector<Neighbor>& out)
      : k_(k), skip_(skip), ids_(ids), alive_(alive), out_(out) {
    out_.clear();
  }
  std::uint32_t offset = 0;  ///< added to the local indices a tree reports
  bool full() const { return out_.size() == k_; }
  double worstDist() const { return worst_; }
  bool addPoint(double d2, std::uint32_t local) {
    const std::uint32_t index = local + offset;
    if (index == skip_ || k_ == 0) return true;
    if (full() && d2 > out_.back().d2) return true;  // cheap reject before touching ids_
    if (!alive_[index]) return true;                 // removed from the static base tree
    const std::uint64_t id = ids_[index];
    if (full()) {
      if (!closer(d2, id, out_.back().d2, out_.back().id)) return true;
      out_.pop_back();
    }
    // Insertion from the back: the list is short (k) and most arrivals land near its end.
    out_.push_back(Neighbor{index, id, d2});
    for (std::size_t j = out_.size() - 1; j > 0 && closer(d2, id, out_[j - 1].d2, out_[j - 1].id);
         --j)
      std::swap(out_[j], out_[j - 1]);
    if (full()) worst_ = admit_equal(out_.back().d2);
    return true;
  }

 private:
  std::size_t k_;
  std::uint32_t skip_;
  const std::vector<std::uint64_t>& ids_;
  const std::vector<std::uint8_t>& alive_;
  std::vector<Neighbor>& out_;
  double worst_ = std::numeric_limits<double>::max();  // what nanoflann may still offer
};

// Every index with d2 <= radius2 (inclusive).
class RadiusCollector {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  RadiusCollector(double radius2, const std::vector<std::uint8_t>& alive,
                  std::vector<std::uint32_t>& out)
      : r2_(radius2), alive_(alive), out_(out) {
    out_.clear();
  }
  std::uint32_t offset = 0;  ///< added to the local indices a tree reports
  bool full() const { return true; }
  double worstDist() const { return admit_equal(r2_); }
  bool addPoint(double d2, std::uint32_t local) {
    if (d2 <= r2_ && alive_[local + offset]) out_.push_back(local + offset);
    return true;
  }

 private:
  double r2_;
  const std::vector<std::uint8_t>& alive_;
  std::vector<std::uint32_t>& out_;
};

}  // namespace detail

class PointIndex {
 public:
  using index_type = std::uint32_t;
  static constexpr index_type npos = ~index_type{0};

  /// rebuild_min: the dynamic tree may hold this many points before the static one is rebuilt
  /// (it is always allowed a quarter of the static tree's size).
  explicit PointIndex(std::size_t rebuild_min = 4096) : rebuild_min_(rebuild_min) { rebuild(); }
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;
  /// Moves the dataset and the trees (the trees' adaptors stay where they are, on the heap, and
  /// now read the moved dataset).
  PointIndex(PointIndex&& o) noexcept
      : rebuild_min_(o.rebuild_min_),
        pts_(std::move(o.pts_)),
        ids_(std::move(o.ids_)),
        alive_(std::move(o.alive_)),
        live_(o.live_),
        in_tree_(o.in_tree_),
        views_(std::move(o.views_)),
        base_tree_(std::move(o.base_tree_)),
        recent_tree_(std::move(o.recent_tree_)) {
    views_->base.pts = views_->recent.pts = &pts_;
  }
  PointIndex& operator=(PointIndex&& o) noexcept {
    if (this == &o) return *this;
    rebuild_min_ = o.rebuild_min_;
    pts_ = std::move(o.pts_);
    ids_ = std::move(o.ids_);
    alive_ = std::move(o.alive_);
    live_ = o.live_;
    in_tree_ = o.in_tree_;
    // Trees first: each refers to its adaptor in views_, which must outlive it.
    base_tree_ = std::move(o.base_tree_);
    recent_tree_ = std::move(o.recent_tree_);
    views_ = std::move(o.views_);
    views_->base.pts = views_->recent.pts = &pts_;
    return *this;
  }

  /// Appends a point; it joins the search structure at the next flush().
  index_type append(std::uint64_t id, const Point3d& p) {
    if (pts_.size() >= npos - 1)
      detail::invalid_argument("PointIndex: more than 2^32 - 2 dataset entries (compact first)");
    pts_.push_back(p);
    ids_.push_back(id);
    alive_.push_back(1);
    ++live_;
    return static_cast<index_type>(pts_.size() - 1);
  }
  /// Makes every point appended since the last flush searchable.
  void flush() {
    if (in_tree_ == pts_.size()) return;
    // The static base tree searches several times faster than nanoflann's dynamic forest;
    // rebuild it once the recent points outgrow a quarter of it (amortised O(log n) per point).
    if (pts_.size() - views_->base.count > std::max(rebuild_min_, views_->base.count / 4)) {
      rebuild();
      return;
    }
    views_->recent.count = pts_.size() - views_->recent.first;
    recent_tree_->addPoints(static_cast<index_type>(in_tree_ - views_->recent.first),
                            static_cast<index_type>(views_->recent.count - 1));
    in_tree_ = pts_.size();
  }
  /// Marks a point dead (never reused).
  void remove(index_type i) {
    if (!alive_[i]) return;
    alive_[i] = 0;
    --live_;
    // The dynamic tree forgets it; the static base skips dead points when they are offered.
    if (i >= views_->recent.first && i < in_tree_)
      recent_tree_->removePoint(i - views_->recent.first);
  }

  std::size_t size() const { return pts_.size(); }  ///< dataset entries, dead ones included
  std::size_t live() const { return live_; }
  std::size_t dead() const { return pts_.size() - live_; }
  bool alive(index_type i) const { return alive_[i] != 0; }
  const Point3d& position(index_type i) const { return pts_[i]; }
  std::uint64_t id(index_type i) const { return ids_[i]; }
  const std::vector<std::uint64_t>& ids() const { return ids_; }

  /// The k nearest live points to point `self` (itself excluded), by (d2, id).
  void knn(index_type self, std::size_t k, std::vector<Neighbor>& out) const {
    detail::KnnCollector c(k, self, ids_, alive_, out);
    search(c, pts_[self]);
  }
  /// Live points within squared distance radius2 of `centre` (inclusive), any order.
  void radius(const Point3d& centre, double radius2, std::vector<index_type>& out) const {
    detail::RadiusCollector c(radius2, alive_, out);
    search(c, centre);
  }

  /// Rebuilds dataset and trees from the live points. Returns old index -> new index (npos for
  /// dead ones) so callers can remap what they keep per index.
  std::vector<index_type> compact() {
    std::vector<index_type> remap(pts_.size(), npos);
    std::vector<Point3d> pts;
    std::vector<std::uint64_t> ids;
    pts.reserve(live_);
    ids.reserve(live_);
    for (std::size_t i = 0; i < pts_.size(); ++i) {
      if (!alive_[i]) continue;
      remap[i] = static_cast<index_type>(pts.size());
      pts.push_back(pts_[i]);
      ids.push_back(ids_[i]);
    }
    pts_.swap(pts);
    ids_.swap(ids);
    alive_.assign(pts_.size(), 1);
    live_ = pts_.size();
    rebuild();
    return remap;
  }

  std::size_t memory_usage() const {
    // Trees: one index per point plus nodes (~ 1 node per 5 points with leaves of 10), and the
    // dynamic forest's per-point tree number.
    return pts_.capacity() * sizeof(Point3d) + ids_.capacity() * sizeof(std::uint64_t) +
           alive_.capacity() + pts_.size() * (sizeof(index_type) + 16) +
           views_->recent.count * sizeof(int);
  }

 private:
  using StaticTree = nanoflann::KDTreeSingleIndexAdaptor<detail::Dist2Metric,
                                                         detail::PointCloudAdaptor, 3, index_type>;
  using DynamicTree =
      nanoflann::KDTreeSingleIndexDynamicAdaptor<detail::Dist2Metric, detail::PointCloudAdaptor, 3,
                                                 index_type>;

  template <class Collector>
  void search(Collector& c, const Point3d& q) const {
    const double v[3] = {q.x, q.y, q.z};
    if (views_->base.count) {
      c.offset = 0;
      base_tree_->findNeighbors(c, v, detail::NanoflannSearchParams());
    }
    if (views_->recent.count) {
      c.offset = static_cast<index_type>(views_->recent.first);
      recent_tree_->findNeighbors(c, v, detail::NanoflannSearchParams());
    }
  }

  // Everything appended so far goes into a new static base tree; the dynamic tree starts empty.
  void rebuild() {
    views_->base = {&pts_, 0, pts_.size()};
    base_tree_.reset();
    if (views_->base.count)
      base_tree_ = std::make_unique<StaticTree>(3, views_->base,
                                                nanoflann::KDTreeSingleIndexAdaptorParams(10));
    views_->recent = {&pts_, pts_.size(), 0};
    recent_tree_ = std::make_unique<DynamicTree>(3, views_->recent,
                                                 nanoflann::KDTreeSingleIndexAdaptorParams(10));
    in_tree_ = pts_.size();
  }

  std::size_t rebuild_min_;
  std::vector<Point3d> pts_;
  std::vector<std::uint64_t> ids_;
  std::vector<std::uint8_t> alive_;
  std::size_t live_ = 0;
  std::size_t in_tree_ = 0;  // dataset entries already searchable
  // The trees keep references to their adaptors: on the heap, so that a move keeps them valid.
  struct Views {
    detail::PointCloudAdaptor base, recent;
  };
  std::unique_ptr<Views> views_ = std::make_unique<Views>();
  std::unique_ptr<StaticTree> base_tree_;     // entries [0, base.count)
  std::unique_ptr<DynamicTree> recent_tree_;  // entries [recent.first, in_tree_), local indices
};

}  // namespace knnocc
