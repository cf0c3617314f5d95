// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Phase 3 of a scan (ScanInserter): apply. The touched bricks with their hit and miss masks (the
// threads' scratches OR-ed) are taken in groups whose concatenation is z, y, x brick order,
// whatever the path or the thread count; the missing map bricks are created in that order by one
// thread (the map's storage order never depends on the path or the thread count); then every
// touched voxel gets exactly one update, occupied first (occupied wins), each brick by one thread.
// The dense scratch is gathered into records (BrickGroups); the hashed scratch is read in place
// through its z, y, x order (HashedUpdates). With one thread and no map memory limit,
// apply_dense_serial does both steps brick row by brick row from the dense scratch, keeping no
// record per touched brick.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "../../map/brick.hpp"
#include "../../map/detail/brick_access.hpp"
#include "../../map/occupancy_map.hpp"
#include "../../raycast/detail/scan_bitmap.hpp"
#include "collect.hpp"
#include "hashed_marks.hpp"
#include "hit_codes.hpp"
#include "thread_scratch.hpp"
#include "work_queue.hpp"

namespace knnocc::detail {

/// One touched brick of a scan and, once created, its map slot.
struct BrickUpdate {
  std::uint64_t coord;
  std::uint32_t slot;
  VoxelMask hit, miss;
};

/// The touched bricks of a scan in groups (memory kept between scans); the groups' concatenation
/// is in z, y, x brick order.
struct BrickGroups {
  std::vector<std::vector<BrickUpdate>> groups;
  std::size_t count = 0;  // groups in use

  void start(std::size_t n) {
    if (groups.size() < n) groups.resize(n);
    for (std::size_t g = 0; g < n; ++g) groups[g].clear();
    count = n;
  }
  std::size_t bricks() const {
    std::size_t n = 0;
    for (std::size_t g = 0; g < count; ++g) n += groups[g].size();
    return n;
  }
  std::size_t memory_usage() const {
    std::size_t bytes = groups.capacity() * sizeof(groups[0]);
    for (const auto& g : groups) bytes += g.capacity() * sizeof(BrickUpdate);
    return bytes;
  }
};

/// How apply_updates walks a scan's touched bricks: groups() groups whose concatenation is in
/// z, y, x order, each(g, f) calling f(coord, slot, hit, miss) for group g's bricks (the slot and
/// masks writable). GroupedUpdates reads BrickGroups' records.
struct GroupedUpdates {
  BrickGroups& bricks;
  std::size_t size() const { return bricks.bricks(); }
  std::size_t groups() const { return bricks.count; }
  template <class F>
  void each(std::size_t g, F&& f) const {
    for (BrickUpdate& u : bricks.groups[g]) f(u.coord, u.slot, u.hit, u.miss);
  }
};

/// The hashed scratch read in place: `order` lists its bricks in z, y, x order (order_hashed), in
/// groups of 256, and `slots` gets their map slots. 8 bytes per touched brick instead of a
/// 144-byte record: far rays touch tens of millions of bricks.
struct HashedUpdates {
  static constexpr std::size_t kGroup = 256;
  HashedMarks& marks;
  const std::vector<std::uint32_t>& order;
  std::vector<std::uint32_t>& slots;
  std::size_t size() const { return order.size(); }
  std::size_t groups() const { return (order.size() + kGroup - 1) / kGroup; }
  template <class F>
  void each(std::size_t g, F&& f) const {
    const std::size_t end = std::min(order.size(), (g + 1) * kGroup);
    static const VoxelMask no_hits{};
    for (std::size_t k = g * kGroup; k < end; ++k) {
      BrickMasks& b = marks[order[k]];
      const VoxelMask* hit = marks.hit_of(order[k]);
      f(b.coord, slots[k], hit ? *hit : no_hits, b.miss);
    }
  }
};

/// The log-odds a scan applies: `hit` to endpoint voxels (unless the hits are rated, each voxel
/// then receiving its own sum: rated_sums.hpp), `miss` to the voxels rays cross.
struct ScanValues {
  float hit = 0.0f, miss = 0.0f;
  bool rated = false;
};

/// Whether brick (bx, by, bz) (brick coordinates) lies in `clip` (null: no clip). A clip is a
/// tile, whose edges are whole bricks: a brick lies in it or outside it.
inline bool brick_in_clip(const KeyBox* clip, std::int64_t bx, std::int64_t by, std::int64_t bz) {
  if (!clip) return true;
  const std::int64_t k[3] = {bx << kBrickBits, by << kBrickBits, bz << kBrickBits};
  for (int a = 0; a < 3; ++a)
    if (k[a] < clip->lo[a] || k[a] > clip->hi[a]) return false;
  return true;
}

/// Gathers the touched bricks of the threads' dense bitmaps (each thread's hit and miss maps of
/// the same box) into `out`, clearing the bitmaps: groups of brick rows, taken by the team's
/// threads in turn (rows differ, so threads share no words). Bricks outside `clip` (when given)
/// are cleared and left out.
template <class Key>
void gather_dense(Team& team, ThreadScratches& scratch, BrickGroups& out,
                  const KeyBox* clip = nullptr) {
  using layout = BrickLayout<Key>;
  const unsigned threads = team.size();
  const ScanBitmap& shape = scratch[0]->hit;  // every bitmap has the scan's box
  const std::int64_t nbx = shape.bricks(0), nby = shape.bricks(1), nrows = nby * shape.bricks(2);
  const std::int64_t* lo = shape.lo();
  const auto groups =
      static_cast<std::size_t>(std::min<std::int64_t>(nrows, threads == 1 ? 1 : 8 * threads));
  const auto rows_per_group = (static_cast<std::size_t>(nrows) + groups - 1) / groups;
  out.start(groups);
  // One thread, one group: room for every brick of the box (capped), so a cold process does not
  // grow it through a doubling series of copies and fresh pages (the reserve stays untouched until
  // written). Not with threads: many large reserves made the threads' mapping churn.
  if (groups == 1)
    out.groups[0].reserve(
        static_cast<std::size_t>(std::min<std::int64_t>(std::int64_t{1} << 16, nrows * nbx)));
  for (unsigned t = 0; t < threads; ++t) {  // here, not in the job: a thread may get no group
    scratch[t]->row_hit.resize(static_cast<std::size_t>(nbx));
    scratch[t]->row_miss.resize(static_cast<std::size_t>(nbx));
  }
  WorkQueue queue(groups);
  auto gather = [&](unsigned w) {
    ThreadScratch& mine = *scratch[w];
    for (std::size_t g; queue.take(g);) {
      const auto first = static_cast<std::int64_t>(g * rows_per_group);
      const auto last = std::min(nrows, static_cast<std::int64_t>((g + 1) * rows_per_group));
      for (std::int64_t r = first; r < last; ++r) {
        const std::int64_t by = r % nby, bz = r / nby;
        for (unsigned t = 0; t < threads; ++t) {
          scratch[t]->hit.take_brick_row(by, bz, mine.row_hit.data());
          scratch[t]->miss.take_brick_row(by, bz, mine.row_miss.data());
        }
        for (std::int64_t bx = 0; bx < nbx; ++bx) {
          VoxelMask& h = mine.row_hit[static_cast<std::size_t>(bx)];
          VoxelMask& m = mine.row_miss[static_cast<std::size_t>(bx)];
          if (!h.any() && !m.any()) continue;
          if (!brick_in_clip(clip, (lo[0] >> kBrickBits) + bx, (lo[1] >> kBrickBits) + by,
                             (lo[2] >> kBrickBits) + bz)) {
            h.clear();
            m.clear();
            continue;
          }
          out.groups[g].push_back(
              {layout::pack_brick((lo[0] >> kBrickBits) + bx, (lo[1] >> kBrickBits) + by,
                                  (lo[2] >> kBrickBits) + bz),
               0, h, m});
          h.clear();
          m.clear();
        }
      }
    }
  };
  team.run(gather);
  for (unsigned t = 0; t < threads; ++t) {
    scratch[t]->hit.mark_clean();
    scratch[t]->miss.mark_clean();
  }
}

/// One thread, no memory limit on the map: what gather_dense and apply_updates do, in the same
/// order, without a record per touched brick (144 bytes each, megabytes for a large scan): each
/// brick row of the thread's dense bitmaps is taken (and cleared), its touched bricks created and
/// updated at once, in z, y, x order. With `codes` the hits come from s.hit_list (HitCodes, sorted
/// here into s.hit_rows) instead of the hit bitmap. A fresh map first gets room for every touched
/// brick (counted in a pass that leaves the scratch as it is), as apply_updates gives it. The same
/// map, pool order and counts as the two-step path. Bricks outside `clip` (when given) are
/// cleared and left out.
template <class Key>
UpdateCounts apply_dense_serial(OccupancyMap<Key>& map, ThreadScratch& s, const ScanValues& values,
                                bool codes = false, const KeyBox* clip = nullptr) {
  using layout = BrickLayout<Key>;
  BrickWriter<Key> writer(map);
  ScanBitmap& hit = s.hit;
  ScanBitmap& miss = s.miss;  // the box's shape (the hit bitmap has it too unless `codes`)
  const std::int64_t nbx = miss.bricks(0), nby = miss.bricks(1), nbz = miss.bricks(2);
  const std::int64_t* lo = miss.lo();
  s.row_hit.resize(static_cast<std::size_t>(nbx));
  s.row_miss.resize(static_cast<std::size_t>(nbx));
  VoxelMask* row_hit = s.row_hit.data();
  VoxelMask* row_miss = s.row_miss.data();
  if (codes) {
    s.hit_rows.clear();
    s.hit_codes.by_row(s.hit_list.data(), s.hit_list.size(),
                       s.hit_rows.room_for(s.hit_list.size()));
  }
  const std::uint32_t* sorted = s.hit_rows.data();
  // Row (by, bz)'s hits into row_hit (from the hit bitmap, clearing it, or from the codes).
  auto take_hits = [&](std::int64_t by, std::int64_t bz) {
    if (!codes) {
      hit.take_brick_row(by, bz, row_hit);
      return;
    }
    s.hit_codes.for_row(sorted, static_cast<std::size_t>(bz * nby + by),
                        [&](std::size_t bx, int local) { row_hit[bx].set(local); });
  };
  if (map.num_bricks() == 0 && !clip) {  // a fresh map: all are new
    // Per brick row, which bricks the rows of each bitmap touch (the codes' bricks added to the
    // miss bitmap's), then how many.
    const bool alike = codes || hit.row_words() == miss.row_words();  // both bits
    const std::int64_t hit_words = alike ? 0 : hit.row_words(), miss_words = miss.row_words();
    s.row_any.resize(static_cast<std::size_t>(hit_words + miss_words));
    std::uint64_t* any_miss = s.row_any.data();
    std::uint64_t* any_hit = alike ? any_miss : any_miss + miss_words;
    std::size_t touched = 0;
    for (std::int64_t bz = 0; bz < nbz; ++bz)
      for (std::int64_t by = 0; by < nby; ++by) {
        std::fill(s.row_any.begin(), s.row_any.end(), std::uint64_t{0});
        miss.or_brick_row(by, bz, any_miss);
        if (codes) {
          s.hit_codes.for_row(sorted, static_cast<std::size_t>(bz * nby + by),
                              [&](std::size_t bx, int) {
                                miss.add_brick(any_miss, static_cast<std::int64_t>(bx));
                              });
        } else {
          hit.or_brick_row(by, bz, any_hit);
        }
        if (alike) {
          touched += miss.bricks_in(any_miss);
          continue;
        }
        for (std::int64_t bx = 0; bx < nbx; ++bx)
          touched += hit.brick_in(any_hit, bx) || miss.brick_in(any_miss, bx);
      }
    writer.reserve_bricks(touched);
  }
  const bool hits_here = !values.rated;  // rated hits carry their own sums
  const bool records = map.change_detection_enabled();
  UpdateCounts c;
  for (std::int64_t bz = 0; bz < nbz; ++bz)
    for (std::int64_t by = 0; by < nby; ++by) {
      take_hits(by, bz);
      miss.take_brick_row(by, bz, row_miss);
      for (std::int64_t bx = 0; bx < nbx; ++bx) {
        VoxelMask& h = row_hit[bx];
        VoxelMask& m = row_miss[bx];
        if (!h.any() && !m.any()) continue;
        if (!brick_in_clip(clip, (lo[0] >> kBrickBits) + bx, (lo[1] >> kBrickBits) + by,
                           (lo[2] >> kBrickBits) + bz)) {
          h.clear();
          m.clear();
          continue;
        }
        const std::uint32_t slot = writer.brick_slot(layout::pack_brick(
            (lo[0] >> kBrickBits) + bx, (lo[1] >> kBrickBits) + by, (lo[2] >> kBrickBits) + bz));
        for (std::size_t i = 0; i < m.w.size(); ++i) m.w[i] &= ~h.w[i];  // hit wins
        auto& brick = writer.brick_at(slot);
        const int masks = int(hits_here && h.any()) + int(m.any());
        if (masks > 1 || brick.known.any() || records) writer.prepare_values(brick);
        if (records) {
          if (hits_here) writer.update_masked(brick, h, values.hit);
          writer.update_masked(brick, m, values.miss);
        } else {
          if (hits_here) c.added += writer.update_brick(brick, h, values.hit);
          c.added += writer.update_brick(brick, m, values.miss);
        }
        if (hits_here) c.occupied += static_cast<std::size_t>(h.count());
        c.free += static_cast<std::size_t>(m.count());
        h.clear();
        m.clear();
      }
    }
  if (!codes) hit.mark_clean();
  miss.mark_clean();
  if (!records) writer.add_known(c.added);
  return c;
}

/// Orders the hashed scratch for HashedUpdates: the other threads' miss masks are OR-ed into the
/// first thread's, whose bricks hold the hits (the others are left empty), and `order` lists the
/// first thread's bricks in z, y, x order; `slots` gets room for their map slots. The first
/// thread's scratch keeps its bricks until the apply has read them. With a memory limit (`limit`
/// > 0; `elsewhere`: the bytes counted against it outside the threads' hashed scratch, `order`
/// and `slots`) the first thread's scratch may grow to what the others leave, and `order` and
/// `slots` are refused (MemoryLimitError) before they grow past it. Bricks outside `clip` (when
/// given) are left out of `order`.
template <class Key>
void order_hashed(ThreadScratches& scratch, unsigned threads, std::vector<std::uint32_t>& order,
                  std::vector<std::uint32_t>& slots, std::size_t limit = 0,
                  std::size_t elsewhere = 0, const KeyBox* clip = nullptr) {
  using layout = BrickLayout<Key>;
  HashedMarks& first = scratch[0]->hashed;
  const auto lists = [&] { return (order.capacity() + slots.capacity()) * sizeof(std::uint32_t); };
  if (limit) {
    std::size_t held = elsewhere + lists();
    for (unsigned t = 1; t < threads; ++t) held += scratch[t]->hashed.memory_usage();
    first.set_cap(limit > held ? limit - held : 1, limit, held);
  }
  for (unsigned t = 1; t < threads; ++t) {
    first.merge_misses(scratch[t]->hashed);
    scratch[t]->hashed.clear();
  }
  const std::size_t n = first.size();
  if (limit) {  // what the two lists add to what is held
    std::size_t held = elsewhere + lists();
    for (unsigned t = 0; t < threads; ++t) held += scratch[t]->hashed.memory_usage();
    std::size_t more = 0;
    if (order.capacity() < n) more += n * sizeof(std::uint32_t);
    if (slots.capacity() < n) more += n * sizeof(std::uint32_t);
    if (held + more > limit) memory_limit_exceeded(limit, held + more);
  }
  auto zyx = [&](std::uint32_t j) {
    const auto o = layout::origin_of(first[j].coord);
    return std::array<std::int64_t, 3>{o[2], o[1], o[0]};
  };
  order.clear();
  for (std::size_t j = 0; j < n; ++j) {
    const auto o = zyx(static_cast<std::uint32_t>(j));
    if (brick_in_clip(clip, o[2] >> kBrickBits, o[1] >> kBrickBits, o[0] >> kBrickBits))
      order.push_back(static_cast<std::uint32_t>(j));
  }
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return zyx(a) < zyx(b); });
  slots.resize(order.size());
}

/// Creates the missing map bricks in group order (serially: the map's value pool is serial), then
/// updates every touched voxel once, occupied first: hit voxels get values.hit (unless rated),
/// miss voxels that are not hits get values.miss. Groups are updated by the team's threads in
/// turn. A brick gets its value array in the serial part unless it has no known voxel and this
/// scan gives it one non-empty mask (only hits or only misses): update_brick then leaves it
/// uniform, without an array (sparse long rays), touching nothing but the brick. Returns the
/// voxels updated (occupied: hit updates, not counting rated ones; free: miss updates). `bricks`:
/// GroupedUpdates or HashedUpdates.
template <class Key, class Updates>
UpdateCounts apply_updates(OccupancyMap<Key>& map, const Updates& bricks, const ScanValues& values,
                           Team& team, ThreadScratches& scratch) {
  BrickWriter<Key> writer(map);
  if (map.num_bricks() == 0) writer.reserve_bricks(bricks.size());  // a fresh map: all are new
  const bool hits_here = !values.rated;  // rated hits carry their own sums
  const bool records = map.change_detection_enabled();
  for (std::size_t g = 0; g < bricks.groups(); ++g)
    bricks.each(
        g, [&](std::uint64_t coord, std::uint32_t& slot, const VoxelMask& hit, VoxelMask& miss) {
          slot = writer.brick_slot(coord);
          for (std::size_t i = 0; i < miss.w.size(); ++i) miss.w[i] &= ~hit.w[i];  // hit wins
          auto& brick = writer.brick_at(slot);
          const int masks = int(hits_here && hit.any()) + int(miss.any());
          if (masks > 1 || brick.known.any() || records) writer.prepare_values(brick);
        });
  UpdateCounts total;
  if (records) {  // records per voxel, in one thread
    for (std::size_t g = 0; g < bricks.groups(); ++g)
      bricks.each(
          g, [&](std::uint64_t, std::uint32_t slot, const VoxelMask& hit, const VoxelMask& miss) {
            auto& brick = writer.brick_at(slot);
            if (hits_here) {
              writer.update_masked(brick, hit, values.hit);
              total.occupied += static_cast<std::size_t>(hit.count());
            }
            writer.update_masked(brick, miss, values.miss);
            total.free += static_cast<std::size_t>(miss.count());
          });
    return total;
  }
  WorkQueue queue(bricks.groups());
  auto update = [&](unsigned w) {
    UpdateCounts& c = scratch[w]->counts;
    c = UpdateCounts{};
    for (std::size_t g; queue.take(g);)
      bricks.each(
          g, [&](std::uint64_t, std::uint32_t slot, const VoxelMask& hit, const VoxelMask& miss) {
            auto& brick = writer.brick_at(slot);
            if (hits_here) {
              c.added += writer.update_brick(brick, hit, values.hit);
              c.occupied += static_cast<std::size_t>(hit.count());
            }
            c.added += writer.update_brick(brick, miss, values.miss);
            c.free += static_cast<std::size_t>(miss.count());
          });
  };
  team.run(update);
  for (unsigned t = 0; t < team.size(); ++t) {
    const UpdateCounts& c = scratch[t]->counts;
    total.occupied += c.occupied;
    total.free += c.free;
    writer.add_known(c.added);
  }
  return total;
}

}  // namespace knnocc::detail
