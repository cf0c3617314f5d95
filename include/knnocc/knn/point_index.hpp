#pragma once
// PointIndex: the map point cloud with stable 64-bit ids, over nanoflann's dynamic KD-tree.
//
// The dataset is append-only: a point added (or moved) gets a new dataset index, a removed index
// is only marked dead in the tree (nanoflann's lazy removePoint) and never reused, and compact()
// rebuilds dataset and tree from the live points when dead entries pile up.
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

// nanoflann's view of the dataset.
struct PointCloudAdaptor {
  const std::vector<Point3d>* pts = nullptr;
  std::size_t kdtree_get_point_count() const { return pts->size(); }
  double kdtree_get_pt(std::size_t i, std::size_t dim) const {
    const Point3d& p = (*pts)[i];
    return dim == 0 ? p.x : (dim == 1 ? p.y : p.z);
  }
  template <class Bbox>
  bool kdtree_get_bbox(Bbox&) const {
    return false;
  }
};

// The tree's metric is dist2() itself, so the tree and brute force agree to the last bit.
struct Dist2Metric {
  using ElementType = double;
  using DistanceType = double;
  const PointCloudAdaptor& data;
  explicit Dist2Metric(const PointCloudAdaptor& d) : data(d) {}
  template <class I>
  double evalMetric(const double* a, I b, std::size_t) const {
    return dist2(Point3d{a[0], a[1], a[2]}, (*data.pts)[static_cast<std::size_t>(b)]);
  }
  template <class U, class V>
  double accum_dist(const U a, const V b, std::size_t) const {
    return (a - b) * (a - b);
  }
};

// nanoflann only offers a point to the result set when dist < worstDist(); reporting the next
// representable value lets equal distances through, so ties are decided by id here.
inline double admit_equal(double d2) {
  return std::nextafter(d2, std::numeric_limits<double>::infinity());
}

// The k nearest by (d2, id), skipping one index (the query point itself).
class KnnCollector {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;

  KnnCollector(std::size_t k, std::uint32_t skip, const std::vector<std::uint64_t>& ids,
               std::vector<Neighbor>& out)
      : k_(k), skip_(skip), ids_(ids), out_(out) {
    out_.clear();
  }
  bool full() const { return out_.size() == k_; }
  double worstDist() const { return worst_; }
  bool addPoint(double d2, std::uint32_t index) {
    if (index == skip_ || k_ == 0) return true;
    if (full() && d2 > out_.back().d2) return true;  // cheap reject before touching ids_
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
  std::vector<Neighbor>& out_;
  double worst_ = std::numeric_limits<double>::max();  // what nanoflann may still offer
};

// Every index with d2 <= radius2 (inclusive).
class RadiusCollector {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  RadiusCollector(double radius2, std::vector<std::uint32_t>& out) : r2_(radius2), out_(out) {
    out_.clear();
  }
  bool full() const { return true; }
  double worstDist() const { return admit_equal(r2_); }
  bool addPoint(double d2, std::uint32_t index) {
    if (d2 <= r2_) out_.push_back(index);
    return true;
  }

 private:
  double r2_;
  std::vector<std::uint32_t>& out_;
};

}  // namespace detail

class PointIndex {
 public:
  using index_type = std::uint32_t;
  static constexpr index_type npos = ~index_type{0};

  PointIndex() { rebuild_tree(); }
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  /// Appends a point; it joins the tree at the next flush().
  index_type append(std::uint64_t id, const Point3d& p) {
    pts_.push_back(p);
    ids_.push_back(id);
    alive_.push_back(1);
    ++live_;
    return static_cast<index_type>(pts_.size() - 1);
  }
  /// Adds every point appended since the last flush to the tree.
  void flush() {
    if (in_tree_ < pts_.size())
      tree_->addPoints(static_cast<index_type>(in_tree_), static_cast<index_type>(pts_.size() - 1));
    in_tree_ = pts_.size();
  }
  /// Marks a point dead (never reused).
  void remove(index_type i) {
    if (!alive_[i]) return;
    alive_[i] = 0;
    --live_;
    if (i < in_tree_) tree_->removePoint(i);
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
    detail::KnnCollector c(k, self, ids_, out);
    search(c, pts_[self]);
  }
  /// Live points within squared distance radius2 of `centre` (inclusive), any order.
  void radius(const Point3d& centre, double radius2, std::vector<index_type>& out) const {
    detail::RadiusCollector c(radius2, out);
    search(c, centre);
  }

  /// Rebuilds dataset and tree from the live points. Returns old index -> new index (npos for
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
    rebuild_tree();
    return remap;
  }

  std::size_t memory_usage() const {
    // The tree keeps one index per point per level group plus nodes; ~ 2 indices per point is a
    // fair estimate for nanoflann's logarithmic forest with leaves of 10.
    return pts_.capacity() * sizeof(Point3d) + ids_.capacity() * sizeof(std::uint64_t) +
           alive_.capacity() + pts_.size() * (sizeof(int) + 2 * sizeof(index_type) + 8);
  }

 private:
  using Tree = nanoflann::KDTreeSingleIndexDynamicAdaptor<detail::Dist2Metric,
                                                          detail::PointCloudAdaptor, 3, index_type>;

  template <class Collector>
  void search(Collector& c, const Point3d& q) const {
    const double v[3] = {q.x, q.y, q.z};
    tree_->findNeighbors(c, v, detail::NanoflannSearchParams());
  }

  void rebuild_tree() {
    adaptor_.pts = &pts_;
    tree_ = std::make_unique<Tree>(3, adaptor_, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    in_tree_ = pts_.size();
  }

  std::vector<Point3d> pts_;
  std::vector<std::uint64_t> ids_;
  std::vector<std::uint8_t> alive_;
  std::size_t live_ = 0;
  std::size_t in_tree_ = 0;
  detail::PointCloudAdaptor adaptor_;
  std::unique_ptr<Tree> tree_;
};

}  // namespace knnocc
