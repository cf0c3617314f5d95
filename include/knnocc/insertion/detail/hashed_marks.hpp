#pragma once
// The hashed scratch of a scan (ScanInserter, phase 2, when the dense box does not fit): one
// thread's touched bricks, each with a hit and a miss mask, found through a hash of brick
// coordinates. Slower than the dense scratch per voxel, but its size follows the voxels the rays
// touch, not the scan's box. Its memory can be capped (set_cap): a new brick past the cap reports
// MemoryLimitError, so that a map's memory limit covers the inserter's scratch too.

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

/// A touched brick of the hashed scratch.
struct BrickMasks {
  std::uint64_t coord = 0;  // packed brick coordinate (BrickLayout)
  VoxelMask hit, miss;
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
    if (cap_ && memory_usage() + growth_bytes() > cap_) {  // no room to grow: found, or refused
      const std::uint32_t i = index_.find(coord);
      if (i == FlatIndex::kNone)
        memory_limit_exceeded(limit_, elsewhere_ + memory_usage() + growth_bytes());
      last_ = i;
      last_coord_ = coord;
      return brick(i);
    }
    bool inserted = false;
    last_ = index_.find_or_insert(coord, static_cast<std::uint32_t>(used_), inserted);
    last_coord_ = coord;
    if (inserted) {
      if (used_ == blocks_.size() * kBlock)
        blocks_.push_back(std::make_unique<BrickMasks[]>(kBlock));
      BrickMasks& b = brick(used_++);
      b.coord = coord;
      b.hit.clear();
      b.miss.clear();
    }
    return brick(last_);
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
    last_ = FlatIndex::kNone;
  }

  /// Bytes held (kept between scans).
  std::size_t memory_usage() const {
    return blocks_.size() * kBlock * sizeof(BrickMasks) + blocks_.capacity() * sizeof(blocks_[0]) +
           index_.memory_usage();
  }
  /// Caps memory_usage() at `cap` bytes (0: no cap): adding a brick that would pass it reports
  /// MemoryLimitError(limit, needed), needed being `elsewhere` (the memory counted against the
  /// same limit outside this scratch) plus what this scratch would hold.
  void set_cap(std::size_t cap, std::size_t limit, std::size_t elsewhere) {
    cap_ = cap;
    limit_ = limit;
    elsewhere_ = elsewhere;
  }

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

  FlatIndex index_;  // brick coordinate -> index in the blocks
  std::vector<std::unique_ptr<BrickMasks[]>> blocks_;
  std::size_t used_ = 0;
  std::uint64_t last_coord_ = 0;
  std::uint32_t last_ = FlatIndex::kNone;
  std::size_t cap_ = 0, limit_ = 0, elsewhere_ = 0;
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
