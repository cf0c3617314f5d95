// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The bricks of an OccupancyMap for the parts that write or read whole bricks at once: the scan
// apply (insertion/detail/brick_updates.hpp), the .bt/.ot reader and writer
// (io/octomap_tree.hpp), the scan inserter's scratch and the live mapper's regional replay
// (live/). These members keep the map's invariants (the known count, value arrays, memory limit,
// change detection) only when used as OccupancyMap documents them, so they are not part of the
// map's public surface: a writer or reader is made from the map where it is needed.

#include <cstddef>
#include <cstdint>

#include "../occupancy_map.hpp"

namespace knnocc::detail {

/// Write access to a map's bricks (see OccupancyMap's "brick access for whole-scan writers").
template <class Key>
class BrickWriter {
 public:
  using Map = OccupancyMap<Key>;
  using Brick = typename Map::Brick;

  explicit BrickWriter(Map& map) : map_(&map) {}

  std::uint32_t brick_slot(std::uint64_t coord) { return map_->brick_slot(coord); }
  Brick& brick_at(std::uint32_t slot) { return map_->brick_at(slot); }
  void reserve_bricks(std::size_t more) { map_->reserve_bricks(more); }
  void prepare_values(Brick& b) { map_->prepare_values(b); }
  void fill_brick(Brick& b, float v) { map_->fill_brick(b, v); }
  void update_masked(Brick& b, const VoxelMask& mask, float delta) {
    map_->update_masked(b, mask, delta);
  }
  std::size_t update_brick(Brick& b, const VoxelMask& mask, float delta) {
    return map_->update_brick(b, mask, delta);
  }
  void add_known(std::size_t voxels) { map_->add_known(voxels); }
  void copy_brick_from(const Map& other, std::uint64_t coord) {
    map_->copy_brick_from(other, coord);
  }

 private:
  Map* map_;
};

/// Read access to a map's bricks: storage order, the brick index, one brick by coordinate.
template <class Key>
class BrickReader {
 public:
  using Map = OccupancyMap<Key>;
  using Brick = typename Map::Brick;

  explicit BrickReader(const Map& map) : map_(&map) {}

  const BigVector<Brick>& bricks() const { return map_->bricks(); }
  const FlatIndex& brick_index() const { return map_->brick_index(); }
  const Brick* find_brick(std::uint64_t coord) const { return map_->find_brick(coord); }

 private:
  const Map* map_;
};

template <class Key>
BrickReader<Key> brick_reader(const OccupancyMap<Key>& map) {
  return BrickReader<Key>(map);
}

}  // namespace knnocc::detail
