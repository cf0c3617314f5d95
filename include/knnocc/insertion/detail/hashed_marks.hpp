// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The hashed scratch of a scan (ScanInserter, phase 2, when the dense box does not fit): one
// thread's touched bricks, each with a miss mask, found through a hash of brick coordinates; the
// few bricks that hold endpoints also get a hit mask, kept apart (rays touch far more bricks than
// endpoints do, so a hit mask in every brick would be mostly empty). Slower than the dense scratch
// per voxel, but its size follows the voxels the rays touch, not the scan's box. Its memory can be
// capped (set_cap): a new brick past the cap reports MemoryLimitError, so that a map's memory limit
// covers the inserter's scratch too, and the cap can count the map bricks the scratch will add
// (count_map_bricks).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "../../core/detail/flat_index.hpp"
#include "../../core/memory_limit.hpp"
#include "../../map/brick.hpp"
#include "../../raycast/dda.hpp"

namespace knnocc::detail {

/// A touched brick of the hashed scratch (its hits, if any: HashedMarks::hit_of).
struct BrickMasks {
  std::uint64_t coord = 0;  // packed brick coordinate (BrickLayout)
  VoxelMask miss;
};

/// One thread's touched bricks (memory kept between scans), in blocks of kBlock: growing never
/// copies the bricks already there, and never needs more than one new block at once.
class HashedMarks {
 public:
  static constexpr std::size_t kBlockBits = 11, kBlock = std::size_t{1} << kBlockBits;

  std::size_t size() const { return used_; }
  const BrickMasks& operator[](std::size_t i) const { return brick(i); }
  BrickMasks& operator[](std::size_t i) { return brick(i); }

  /// The brick `coord`, added with empty masks when new. References stay valid until clear().
  BrickMasks& at(std::uint64_t coord) {
    if (last_ != FlatIndex::kNone && coord == last_coord_) return brick(last_);
    if (cap_ && held_with(1) > cap_) {  // maybe no room for another brick: found, or refused
      const std::uint32_t i = index_.find(coord);
      if (i != FlatIndex::kNone) {
        last_ = i;
        last_coord_ = coord;
        return brick(i);
      }
      const std::size_t need = held_with(missing_from_map(coord) ? 1 : 0);
      if (need > cap_) memory_limit_exceeded(limit_, elsewhere_ + need);
    }
    bool inserted = false;
    last_ = index_.find_or_insert(coord, static_cast<std::uint32_t>(used_), inserted);
    last_coord_ = coord;
    if (inserted) {
      if (used_ == blocks_.size() * kBlock)
        blocks_.push_back(std::make_unique<BrickMasks[]>(kBlock));
      BrickMasks& b = brick(used_++);
      b.coord = coord;
      b.miss.clear();
      fresh_ += missing_from_map(coord);
    }
    return brick(last_);
  }
  /// Marks voxel `local` of brick `coord` as hit (the brick is added when new).
  void set_hit(std::uint64_t coord, int local) {
    at(coord);
    const auto j = last_;
    std::uint32_t slot = hit_index_.find(j);
    if (slot == FlatIndex::kNone) {
      const std::size_t need = memory_usage() + hit_growth_bytes() + map_bytes(fresh_);
      if (cap_ && need > cap_) memory_limit_exceeded(limit_, elsewhere_ + need);
      bool inserted = false;
      slot = hit_index_.find_or_insert(j, static_cast<std::uint32_t>(hits_.size()), inserted);
      hits_.emplace_back();
    }
    hits_[slot].set(local);
  }
  /// The hit mask of the i-th brick, or null when it holds no hit.
  const VoxelMask* hit_of(std::size_t i) const {
    const std::uint32_t slot = hit_index_.find(i);
    return slot == FlatIndex::kNone ? nullptr : &hits_[slot];
  }

  /// ORs other's miss masks into this scratch's bricks.
  void merge_misses(const HashedMarks& other) {
    for (std::size_t j = 0; j < other.used_; ++j) {
      const BrickMasks& from = other.brick(j);
      BrickMasks& into = at(from.coord);
      for (std::size_t i = 0; i < into.miss.w.size(); ++i) into.miss.w[i] |= from.miss.w[i];
    }
  }
  void clear() {
    used_ = 0;
    index_.clear();
    hit_index_.clear();
    hits_.clear();
    fresh_ = 0;
    last_ = FlatIndex::kNone;
  }

  /// Bytes held (kept between scans).
  std::size_t memory_usage() const {
    return blocks_.size() * kBlock * sizeof(BrickMasks) + blocks_.capacity() * sizeof(blocks_[0]) +
           index_.memory_usage() + hit_index_.memory_usage() + hits_.capacity() * sizeof(VoxelMask);
  }
  /// Caps memory_usage() at `cap` bytes (0: no cap): adding a brick that would pass it reports
  /// MemoryLimitError(limit, needed), needed being `elsewhere` (the memory counted against the
  /// same limit outside this scratch) plus what this scratch would hold.
  void set_cap(std::size_t cap, std::size_t limit, std::size_t elsewhere) {
    cap_ = cap;
    limit_ = limit;
    elsewhere_ = elsewhere;
  }
  /// Counts against the cap the map bricks this scratch's bricks will become: `bytes_each` for
  /// every brick that `map_bricks` (the map's brick index) lacks, beyond the `spare` bricks the
  /// map has room for already. A scan that cannot fit is then refused before its scratch alone
  /// fills the cap. Null: not counted. Kept through clear().
  void count_map_bricks(const FlatIndex* map_bricks, std::size_t bytes_each, std::size_t spare) {
    map_bricks_ = map_bricks;
    map_brick_bytes_ = bytes_each;
    map_spare_ = spare;
  }
  /// Bricks added since clear() that the map lacks (counted with count_map_bricks only).
  std::size_t bricks_new_to_map() const { return fresh_; }

 private:
  BrickMasks& brick(std::size_t i) { return blocks_[i >> kBlockBits][i & (kBlock - 1)]; }
  const BrickMasks& brick(std::size_t i) const {
    return blocks_[i >> kBlockBits][i & (kBlock - 1)];
  }

  // How much memory_usage() grows when the next new brick is added.
  std::size_t growth_bytes() const {
    std::size_t grow = index_.growth_bytes(index_.size() + 1);
    if (used_ == blocks_.size() * kBlock) {
      grow += kBlock * sizeof(BrickMasks);
      if (blocks_.size() == blocks_.capacity())
        grow += std::max<std::size_t>(blocks_.capacity(), 1) * sizeof(blocks_[0]);
    }
    return grow;
  }

  // memory_usage(), the next brick's growth, and the map's growth for `more` more new map bricks.
  std::size_t held_with(std::size_t more) const {
    return memory_usage() + growth_bytes() + map_bytes(fresh_ + more);
  }
  bool missing_from_map(std::uint64_t coord) const {
    return map_bricks_ && map_bricks_->find(coord) == FlatIndex::kNone;
  }
  // What n new map bricks add to the map beyond the room it has.
  std::size_t map_bytes(std::size_t n) const {
    return n > map_spare_ ? (n - map_spare_) * map_brick_bytes_ : 0;
  }

  // How much memory_usage() grows when the next brick gets a hit mask.
  std::size_t hit_growth_bytes() const {
    std::size_t grow = hit_index_.growth_bytes(hit_index_.size() + 1);
    if (hits_.size() == hits_.capacity())
      grow += std::max<std::size_t>(hits_.capacity(), 1) * sizeof(VoxelMask);
    return grow;
  }

  FlatIndex index_;              // brick coordinate -> index in the blocks
  FlatIndex hit_index_;          // brick index -> its hit mask in hits_
  std::vector<VoxelMask> hits_;  // hit masks of the bricks holding endpoints
  std::vector<std::unique_ptr<BrickMasks[]>> blocks_;
  std::size_t used_ = 0;
  std::uint64_t last_coord_ = 0;
  std::uint32_t last_ = FlatIndex::kNone;
  std::size_t cap_ = 0, limit_ = 0, elsewhere_ = 0;
  const FlatIndex* map_bricks_ = nullptr;  // count_map_bricks
  std::size_t map_brick_bytes_ = 0, map_spare_ = 0, fresh_ = 0;
};

/// walk_ray()'s visitor for the hashed scratch: marks the voxel in its brick's miss mask, looking
/// the brick up only when the walk enters another brick (a Key object per voxel went through
/// memory and stalled the CPU). Counts the visits.
template <class Key>
struct HashedMissMarks {
  HashedMarks& marks;
  std::size_t visits = 0;
  VoxelMask* miss = nullptr;  // of brick `coord`
  std::uint64_t coord = 0;

  bool operator()(const KeyPosition& p) {
    if (!p.in_range(Key::extent)) return false;
    const std::uint64_t c = BrickLayout<Key>::pack_brick(p.k[0] >> kBrickBits, p.k[1] >> kBrickBits,
                                                         p.k[2] >> kBrickBits);
    if (!miss || c != coord) {
      miss = &marks.at(c).miss;
      coord = c;
    }
    constexpr std::int64_t m = kBrickEdge - 1;
    miss->set(static_cast<int>((p.k[0] & m) | ((p.k[1] & m) << kBrickBits) |
                               ((p.k[2] & m) << (2 * kBrickBits))));
    ++visits;
    return true;
  }
};

}  // namespace knnocc::detail
