// expect: private
// A brick's values are written by the scan apply through detail::BrickWriter, never by users:
// update_brick leaves the map's known-voxel count to its caller.
#include <knnocc/map/occupancy_map.hpp>
int main() {
  knnocc::OccupancyMap<> map(0.1);
  knnocc::VoxelMask mask;
  mask.set(0);
  knnocc::OccupancyMap<>::Brick brick;
  return static_cast<int>(map.update_brick(brick, mask, 0.85f));
}
