// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// OccupancyMap: sparse hashed voxel storage with OctoMap's log-odds update and clamping.
//
// Layout: a FlatIndex maps a brick coordinate to a Brick (8x8x8 voxels, see brick.hpp). A brick
// is the bottom three levels of an octree stored flat: a known-mask (which voxels have a value)
// and either 512 float log-odds or, after compact(), one value shared by all its known voxels.
// The 512-value arrays come from the map's ValuePool (large slabs, value_pool.hpp).
// Coarser octree levels are implicit: the value of a node at depth d is the max over its known
// leaves (OctoMap's inner-node rule), computed on demand by logodds_at_depth().
//
// Only finest-level values are stored, so OctoMap's pruning (merging 8 equal children) has
// nothing to change here: a pruned OctoMap and this map hold the same leaf values.
//
// Thread safety: const member functions touch no shared mutable state and may run concurrently
// from many threads while no thread writes. Writers (update, set, Accessor, compact, clear) need
// exclusive access. An Accessor is a per-thread cursor; do not share one between threads.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "../core/config.hpp"
#include "../core/detail/flat_index.hpp"
#include "../core/grid.hpp"
#include "../core/key.hpp"
#include "../core/log_odds.hpp"
#include "../core/memory_limit.hpp"
#include "brick.hpp"
#include "detail/brick_values.hpp"
#include "value_pool.hpp"

namespace knnocc {

/// Clamping and occupancy threshold of a map (OctoMap's defaults).
struct OccupancyParams {
  float clamp_min = logodds(0.1192);         ///< -2.00002789
  float clamp_max = logodds(0.971);          ///< 3.51103067
  float occupancy_threshold = logodds(0.5);  ///< 0: occupied iff logodds >= threshold

  /// Throws std::invalid_argument (aborts without exceptions) unless min < threshold <= max.
  void validate() const {
    if (!(std::isfinite(clamp_min) && std::isfinite(clamp_max) &&
          std::isfinite(occupancy_threshold)))
      detail::invalid_argument("occupancy parameters must be finite");
    if (!(clamp_min < clamp_max))
      detail::invalid_argument("clamp_min must be smaller than clamp_max");
    if (!(occupancy_threshold >= clamp_min && occupancy_threshold <= clamp_max))
      detail::invalid_argument("occupancy_threshold must lie within [clamp_min, clamp_max]");
  }
};

/// Counts of known finest-level voxels.
struct VoxelCounts {
  std::size_t occupied = 0;
  std::size_t free = 0;
  std::size_t known() const { return occupied + free; }
};

namespace detail {
template <class Key>
class BrickWriter;
template <class Key>
class BrickReader;
}  // namespace detail

template <class Key = OcKey>
class OccupancyMap {
 public:
  using key_type = Key;
  using grid_type = Grid<Key>;
  using layout = BrickLayout<Key>;

  struct Brick {
    std::uint64_t coord = 0;  ///< packed brick coordinate (BrickLayout)
    VoxelMask known;          ///< voxels that hold a value
    float* values = nullptr;  ///< 512 log-odds (the map's pool), null: `uniform`
    float uniform = 0.0f;     ///< the value of every known voxel when values is null

    float get(int i) const { return values ? values[static_cast<std::size_t>(i)] : uniform; }
  };

  explicit OccupancyMap(double resolution, OccupancyParams params = {})
      : grid_(resolution), params_(params) {
    params_.validate();
  }

  const grid_type& grid() const { return grid_; }
  double resolution() const { return grid_.resolution(); }
  const OccupancyParams& params() const { return params_; }

  bool is_occupied(float logodds_value) const {
    return logodds_value >= params_.occupancy_threshold;
  }

  // ---- point queries -------------------------------------------------------------------------

  /// Log-odds of a finest-level voxel, or nullopt when unknown.
  std::optional<float> logodds(const Key& key) const {
    const std::uint32_t slot = index_.find(layout::brick_of(key));
    if (slot == detail::FlatIndex::kNone) return std::nullopt;
    const Brick& b = bricks_[slot];
    const int i = layout::local_of(key);
    if (!b.known.test(i)) return std::nullopt;
    return b.get(i);
  }
  bool is_known(const Key& key) const { return logodds(key).has_value(); }
  /// nullopt when unknown.
  std::optional<bool> is_occupied(const Key& key) const {
    const auto v = logodds(key);
    if (!v) return std::nullopt;
    return is_occupied(*v);
  }

  /// Value of the depth-d node containing `key` (0 = root, Key::depth = leaf): the max over its
  /// known leaves, as OctoMap's inner nodes; nullopt when none is known.
  std::optional<float> logodds_at_depth(const Key& key, int d) const {
    if (d >= Key::depth) return logodds(key);
    if (d < 0) d = 0;
    const int shift = Key::depth - d;
    std::array<std::int64_t, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = (static_cast<std::int64_t>(key[a]) >> shift) << shift;
      hi[a] = lo[a] + (std::int64_t{1} << shift) - 1;
    }
    float best = -std::numeric_limits<float>::infinity();
    bool any = false;
    visit_box(lo, hi, [&](const Key&, float v) {
      any = true;
      best = std::max(best, v);
    });
    if (!any) return std::nullopt;
    return best;
  }

  // ---- updates -------------------------------------------------------------------------------

  /// OctoMap's updateNode(key, delta): a voxel at the clamp bound in the direction of the update
  /// is left unchanged; otherwise value += delta (a new voxel starts at 0) and is clamped.
  /// Returns the new value.
  float update(const Key& key, float delta) {
    Brick& b = bricks_[brick_slot_for_write(layout::brick_of(key))];
    return update_voxel(b, layout::local_of(key), delta);
  }

  /// Sets a voxel's log-odds, clamped into [clamp_min, clamp_max] (OctoMap's setNodeValue).
  void set(const Key& key, float value) {
    Brick& b = bricks_[brick_slot_for_write(layout::brick_of(key))];
    const int i = layout::local_of(key);
    const float v = clamp(value);
    track_change(b, i, v);
    write(b, i, v);
  }

  /// A per-thread write cursor that remembers the last brick, so walking along a ray rarely
  /// hashes. Valid until the map is cleared or destroyed.
  class Accessor {
   public:
    explicit Accessor(OccupancyMap& map) : map_(&map) {}
    float update(const Key& key, float delta) {
      return map_->update_voxel(brick(key), layout::local_of(key), delta);
    }
    /// The brick holding `key`, created when missing.
    Brick& brick(const Key& key) {
      const std::uint64_t c = layout::brick_of(key);
      if (slot_ == detail::FlatIndex::kNone || c != coord_) {
        slot_ = map_->brick_slot_for_write(c);
        coord_ = c;
      }
      return map_->bricks_[slot_];
    }

   private:
    OccupancyMap* map_;
    std::uint64_t coord_ = 0;
    std::uint32_t slot_ = detail::FlatIndex::kNone;
  };
  Accessor accessor() { return Accessor(*this); }

  // ---- iteration -----------------------------------------------------------------------------

  /// Calls f(key, logodds) for every known finest-level voxel (in storage order).
  template <class F>
  void for_each_voxel(F&& f) const {
    for (const Brick& b : bricks_)
      b.known.for_each([&](int i) { f(layout::key_of(b.coord, i), b.get(i)); });
  }

  /// Calls f(key, logodds) for every known voxel with lo[a] <= key[a] <= hi[a] on all axes.
  template <class F>
  void for_each_voxel_in_bbox(const Key& lo, const Key& hi, F&& f) const {
    visit_box({lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}, f);
  }

  /// Same, with a box in world coordinates (clipped to the key range).
  template <class F>
  void for_each_voxel_in_bbox(const std::array<double, 3>& min, const std::array<double, 3>& max,
                              F&& f) const {
    std::array<std::int64_t, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
      // Same rounding as Grid::coord_to_index, then clipped to the key range.
      const double inv = 1.0 / grid_.resolution();
      const double l = std::max(std::floor(inv * min[a]), -static_cast<double>(Key::center));
      const double h = std::min(std::floor(inv * max[a]), static_cast<double>(Key::center) - 1);
      if (!(l <= h)) return;
      lo[a] = static_cast<std::int64_t>(l) + Key::center;
      hi[a] = static_cast<std::int64_t>(h) + Key::center;
    }
    visit_box(lo, hi, f);
  }

  /// Number of known finest-level voxels.
  std::size_t num_voxels() const { return known_count_; }
  std::size_t num_bricks() const { return bricks_.size(); }
  bool empty() const { return known_count_ == 0; }

  VoxelCounts count_voxels() const {
    VoxelCounts c;
    for (const Brick& b : bricks_) {  // per brick, no key built per voxel
      const auto known = static_cast<std::size_t>(b.known.count());
      std::size_t occupied = 0;
      if (!b.values)
        occupied = is_occupied(b.uniform) ? known : 0;
      else
        b.known.for_each(
            [&](int i) { occupied += is_occupied(b.values[static_cast<std::size_t>(i)]); });
      c.occupied += occupied;
      c.free += known - occupied;
    }
    return c;
  }

  // ---- memory --------------------------------------------------------------------------------

  /// Compaction (the analogue of OctoMap's pruning): every brick whose known voxels all hold the
  /// same value drops its 512-value array, and the remaining arrays move into a pool just large
  /// enough for them. Values and queries are unchanged. Returns the number of bricks compacted by
  /// this call.
  std::size_t compact() {
    std::size_t n = 0;
    for (Brick& b : bricks_) {
      if (!b.values) continue;
      bool first = true, uniform = true;
      float u = 0.0f;
      b.known.for_each([&](int i) {
        const float v = b.values[static_cast<std::size_t>(i)];
        if (first) {
          u = v;
          first = false;
        } else if (v != u) {
          uniform = false;
        }
      });
      if (!uniform) continue;
      b.values = nullptr;  // the old pool goes as a whole below
      b.uniform = u;
      ++n;
    }
    if (n > 0) {
      std::size_t live = 0;
      for (const Brick& b : bricks_) live += b.values != nullptr;
      ValuePool packed;
      packed.reserve(live);
      for (Brick& b : bricks_) {
        if (!b.values) continue;
        float* v = packed.allocate();
        std::copy(b.values, b.values + kBrickVoxels, v);
        b.values = v;
      }
      pool_ = std::move(packed);
    }
    return n;
  }

  /// Bounds memory_usage() to `bytes` (0, the default: no bound). A write that needs a new brick
  /// or value array whose storage would take memory_usage() past the limit reports
  /// MemoryLimitError (core/memory_limit.hpp: a std::bad_alloc; without exceptions a message and
  /// abort()) before allocating it. What was written before stays; a whole-scan insertion
  /// (ScanInserter) refused midway may have applied part of the scan; ScanInserter counts its
  /// scratch against the same limit (ScanInserter::memory_usage). compact() and the change set
  /// are not bounded (compact() needs at most the value arrays once more, then frees them).
  void set_memory_limit(std::size_t bytes) { memory_limit_ = bytes; }
  std::size_t memory_limit() const { return memory_limit_; }

  /// Bytes held by the map (bricks, value slabs, hash index, change set).
  std::size_t memory_usage() const {
    std::size_t bytes = sizeof(*this) + bricks_.capacity() * sizeof(Brick) + index_.memory_usage() +
                        pool_.memory_usage();
    bytes += changed_.size() * (sizeof(std::uint64_t) + sizeof(bool) + 2 * sizeof(void*));
    return bytes;
  }

  void clear() {
    bricks_.clear();
    pool_.clear();
    index_.reset();
    changed_.clear();
    known_count_ = 0;
  }

  // ---- change detection (OctoMap's enableChangeDetection semantics) --------------------------

  /// When on, every update records its key: `true` for a voxel that became known, `false` for a
  /// known voxel whose occupancy flipped; a second flip of a not-new voxel removes the record.
  void enable_change_detection(bool on) { change_detection_ = on; }
  bool change_detection_enabled() const { return change_detection_; }
  void reset_change_detection() { changed_.clear(); }
  std::size_t num_changed_keys() const { return changed_.size(); }
  /// Calls f(key, became_known) for every recorded key.
  template <class F>
  void for_each_changed_key(F&& f) const {
    for (const auto& [packed, created] : changed_) f(Key::unpack(packed), created);
  }

 private:
  template <class>
  friend class detail::BrickWriter;
  template <class>
  friend class detail::BrickReader;

  /// Applies `delta` to voxel i of brick b with OctoMap's early abort and clamping.
  float update_voxel(Brick& b, int i, float delta) {
    if (b.known.test(i)) {
      const float v = b.get(i);
      if ((delta >= 0 && v >= params_.clamp_max) || (delta <= 0 && v <= params_.clamp_min))
        return v;
      const float nv = clamp(v + delta);
      track_change(b, i, nv);
      write(b, i, nv);
      return nv;
    }
    const float nv = clamp(0.0f + delta);
    track_change(b, i, nv);
    write(b, i, nv);
    return nv;
  }

  /// update_voxel(b, i, delta) for every voxel i in `mask` (a whole scan's hits or misses of one
  /// brick): the same float operations voxel by voxel, with the known mask and count updated a
  /// word at a time.
  void update_masked(Brick& b, const VoxelMask& mask, float delta) {
    if (change_detection_) {  // per-voxel bookkeeping
      mask.for_each([&](int i) { update_voxel(b, i, delta); });
      return;
    }
    known_count_ += update_brick(b, mask, delta);
  }

  // ---- brick access for whole-scan writers: detail::BrickWriter / BrickReader -----------------
  // (map/detail/brick_access.hpp). These keep the map's invariants only when used as documented.

  /// Slot of the brick with packed coordinate `coord`; a missing brick is created empty, without
  /// its value array (prepare_values or update_brick allocates it). Slots stay valid until
  /// clear().
  std::uint32_t brick_slot(std::uint64_t coord) {
    if (memory_limit_ && index_.find(coord) == detail::FlatIndex::kNone) check_new_brick(false);
    bool inserted = false;
    const auto next = static_cast<std::uint32_t>(bricks_.size());
    const std::uint32_t slot = index_.find_or_insert(coord, next, inserted);
    if (inserted) bricks_.emplace_back().coord = coord;
    return slot;
  }
  Brick& brick_at(std::uint32_t slot) { return bricks_[slot]; }

  /// Room for `more` bricks beyond those stored: one allocation instead of a doubling series
  /// (growth stays geometric when called repeatedly).
  void reserve_bricks(std::size_t more) {
    const std::size_t need = bricks_.size() + more;
    if (memory_limit_) {  // the whole scan's bricks refused before any is made
      std::size_t grow = index_.growth_bytes(need);
      if (bricks_.capacity() < need)
        grow += (std::max(need, 2 * bricks_.capacity()) - bricks_.capacity()) * sizeof(Brick);
      check_growth(grow);  // value arrays are checked one by one (prepare_values)
    }
    if (bricks_.capacity() < need) bricks_.reserve(std::max(need, 2 * bricks_.capacity()));
    index_.reserve(need);
  }

  /// Gives `b` its value array when it has none (new or compacted), filled with its uniform value
  /// where voxels are known. Serial: the pool is shared by all bricks. Writers that update
  /// different bricks from several threads call it for each brick first.
  void prepare_values(Brick& b) {
    if (b.values) return;
    if (memory_limit_) check_growth(pool_.growth_bytes());
    b.values = pool_.allocate();
    // Values of unknown voxels are never read, so a new brick needs no filling.
    if (b.known.any()) std::fill(b.values, b.values + kBrickVoxels, b.uniform);
  }

  /// Makes every voxel of `b` known with value `v` (clamped), as one compacted brick.
  void fill_brick(Brick& b, float v) {
    const auto had = static_cast<std::size_t>(b.known.count());
    pool_.release(b.values);
    b.values = nullptr;
    b.known.w.fill(~std::uint64_t{0});
    b.uniform = clamp(v);
    known_count_ += static_cast<std::size_t>(kBrickVoxels) - had;
  }

  /// update_voxel(b, i, delta) for every voxel i in `mask`, without change detection (callers
  /// check change_detection_enabled()) and without the map's voxel count: returns the number of
  /// voxels that became known, for add_known(). An empty mask never touches `b`. A brick with no
  /// known voxel and no value array (new) takes a non-empty mask as a uniform brick, as compact()
  /// would leave it: every voxel of `mask` gets clamp(0 + delta), bit for bit what the array
  /// would hold, and no array is allocated (sparse rays touch a few voxels of many bricks). Any
  /// other brick without an array (compacted, or made uniform by an earlier update) gets it here
  /// (prepare_values), which is serial.
  /// Threads: update_brick touches nothing but `b` (so different bricks may be updated from
  /// different threads at once) when `b` has its value array, or has no known voxel and gets
  /// this one non-empty update before its next prepare_values(): a writer that updates bricks
  /// from several threads calls prepare_values first for every brick that has known voxels or
  /// will get more than one non-empty mask.
  std::size_t update_brick(Brick& b, const VoxelMask& mask, float delta) {
    if (!mask.any()) return 0;
    if (!b.values && !b.known.any()) {  // new: one update leaves it uniform
      b.uniform = clamp(0.0f + delta);
      b.known = mask;
      return static_cast<std::size_t>(mask.count());
    }
    prepare_values(b);  // compacted or uniform: give it its value array first
    const detail::ValueUpdate u{delta, clamp(0.0f + delta), params_.clamp_min, params_.clamp_max};
#if KNNOCC_AVX2_LANES
    if (detail::cpu_has_avx2())  // the same updates, eight voxels at a time
      detail::update_values_avx2(b.values, mask.w.data(), b.known.w.data(), mask.w.size(), u);
    else
#endif
      detail::update_values_scalar(b.values, mask.w.data(), b.known.w.data(), mask.w.size(), u);
    std::size_t added = 0;  // voxels seen for the first time
    for (std::size_t j = 0; j < mask.w.size(); ++j) {
      added += static_cast<std::size_t>(detail::popcount64(mask.w[j] & ~b.known.w[j]));
      b.known.w[j] |= mask.w[j];
    }
    return added;
  }
  void add_known(std::size_t voxels) { known_count_ += voxels; }

  /// Makes brick `coord` hold exactly what `other` holds there: its known voxels and their
  /// values, none when `other` has no such brick (a regional replay: the brick is recomputed in
  /// another map and copied back). Both maps must have the same resolution and key type. No
  /// change detection is recorded.
  void copy_brick_from(const OccupancyMap& other, std::uint64_t coord) {
    const Brick* src = other.find_brick(coord);
    const bool any = src && src->known.any();
    std::uint32_t slot = index_.find(coord);
    if (slot == detail::FlatIndex::kNone) {
      if (!any) return;
      slot = brick_slot(coord);
    }
    Brick& b = bricks_[slot];
    if (memory_limit_ && any && src->values && !b.values) check_growth(pool_.growth_bytes());
    known_count_ -= static_cast<std::size_t>(b.known.count());
    if (!any) {
      b.known.clear();
      return;
    }
    b.known = src->known;
    known_count_ += static_cast<std::size_t>(b.known.count());
    if (src->values) {
      if (!b.values) b.values = pool_.allocate();
      std::copy(src->values, src->values + kBrickVoxels, b.values);
    } else {
      pool_.release(b.values);
      b.values = nullptr;
      b.uniform = src->uniform;
    }
  }
  /// The brick index (packed brick coordinate -> slot): which bricks exist, for a scan's scratch.
  const detail::FlatIndex& brick_index() const { return index_; }
  const Brick* find_brick(std::uint64_t coord) const {
    const std::uint32_t slot = index_.find(coord);
    return slot == detail::FlatIndex::kNone ? nullptr : &bricks_[slot];
  }
  const detail::BigVector<Brick>& bricks() const { return bricks_; }

  float clamp(float v) const {
    if (v < params_.clamp_min) return params_.clamp_min;
    if (v > params_.clamp_max) return params_.clamp_max;
    return v;
  }

  // Refuses a new brick (with_values: and its value array) that would pass the memory limit.
  void check_new_brick(bool with_values) {
    std::size_t grow = index_.growth_bytes(index_.size() + 1);
    if (with_values) grow += pool_.growth_bytes();
    if (bricks_.size() == bricks_.capacity())
      grow += std::max<std::size_t>(bricks_.capacity(), 1) * sizeof(Brick);
    check_growth(grow);
  }
  void check_growth(std::size_t grow) {
    if (grow == 0) return;
    const std::size_t after = memory_usage() + grow;
    if (after > memory_limit_) detail::memory_limit_exceeded(memory_limit_, after);
  }

  std::uint32_t brick_slot_for_write(std::uint64_t coord) {
    if (memory_limit_ && index_.find(coord) == detail::FlatIndex::kNone) check_new_brick(true);
    bool inserted = false;
    const auto next = static_cast<std::uint32_t>(bricks_.size());
    const std::uint32_t slot = index_.find_or_insert(coord, next, inserted);
    if (inserted) {
      Brick& b = bricks_.emplace_back();
      b.coord = coord;
      b.values = pool_.allocate();
      std::fill(b.values, b.values + kBrickVoxels, 0.0f);
    }
    return slot;
  }

  void write(Brick& b, int i, float v) {
    if (memory_limit_ && !b.values && v != b.uniform) check_growth(pool_.growth_bytes());
    if (!b.known.test(i)) {
      b.known.set(i);
      ++known_count_;
    }
    if (!b.values) {
      if (v == b.uniform) return;
      b.values = pool_.allocate();
      std::fill(b.values, b.values + kBrickVoxels, b.uniform);
    }
    b.values[static_cast<std::size_t>(i)] = v;
  }

  // Called before write(): compares the old state of voxel i with the new value.
  void track_change(const Brick& b, int i, float new_value) {
    if (!change_detection_) return;
    const std::uint64_t packed = layout::key_of(b.coord, i).pack();
    if (!b.known.test(i)) {
      changed_.emplace(packed, true);
      return;
    }
    if (is_occupied(b.get(i)) == is_occupied(new_value)) return;
    auto it = changed_.find(packed);
    if (it == changed_.end())
      changed_.emplace(packed, false);
    else if (!it->second)  // a voxel recorded as new stays recorded (OctoMap does the same)
      changed_.erase(it);
  }

  // Visits known voxels in the inclusive key box [lo, hi], probing bricks or scanning them all,
  // whichever touches fewer bricks.
  template <class F>
  void visit_box(const std::array<std::int64_t, 3>& lo, const std::array<std::int64_t, 3>& hi,
                 F&& f) const {
    std::array<std::int64_t, 3> blo{}, bhi{};
    double boxes = 1.0;
    for (int a = 0; a < 3; ++a) {
      if (lo[a] > hi[a]) return;
      blo[a] = lo[a] >> kBrickBits;
      bhi[a] = hi[a] >> kBrickBits;
      boxes *= static_cast<double>(bhi[a] - blo[a] + 1);
    }
    auto visit_brick = [&](const Brick& b) {
      const auto o = layout::origin_of(b.coord);
      const bool inside = o[0] >= lo[0] && o[0] + kBrickEdge - 1 <= hi[0] && o[1] >= lo[1] &&
                          o[1] + kBrickEdge - 1 <= hi[1] && o[2] >= lo[2] &&
                          o[2] + kBrickEdge - 1 <= hi[2];
      b.known.for_each([&](int i) {
        const Key k = layout::key_of(b.coord, i);
        if (inside || (k[0] >= lo[0] && k[0] <= hi[0] && k[1] >= lo[1] && k[1] <= hi[1] &&
                       k[2] >= lo[2] && k[2] <= hi[2]))
          f(k, b.get(i));
      });
    };
    if (boxes >= static_cast<double>(bricks_.size())) {
      for (const Brick& b : bricks_) {
        const auto o = layout::origin_of(b.coord);
        if ((o[0] >> kBrickBits) < blo[0] || (o[0] >> kBrickBits) > bhi[0] ||
            (o[1] >> kBrickBits) < blo[1] || (o[1] >> kBrickBits) > bhi[1] ||
            (o[2] >> kBrickBits) < blo[2] || (o[2] >> kBrickBits) > bhi[2])
          continue;
        visit_brick(b);
      }
      return;
    }
    for (std::int64_t x = blo[0]; x <= bhi[0]; ++x)
      for (std::int64_t y = blo[1]; y <= bhi[1]; ++y)
        for (std::int64_t z = blo[2]; z <= bhi[2]; ++z)
          if (const Brick* b = find_brick(layout::pack_brick(x, y, z))) visit_brick(*b);
  }

  grid_type grid_;
  OccupancyParams params_;
  detail::BigVector<Brick> bricks_;
  ValuePool pool_;  // the bricks' value arrays
  detail::FlatIndex index_;
  std::size_t known_count_ = 0;
  std::size_t memory_limit_ = 0;  // 0: none
  bool change_detection_ = false;
  std::unordered_map<std::uint64_t, bool> changed_;
};

}  // namespace knnocc
