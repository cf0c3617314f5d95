// expect: private
// The map's storage (a detail:: container) is not part of its public surface.
#include <knnocc/map/occupancy_map.hpp>
int main() {
  const knnocc::OccupancyMap<> map(0.1);
  return static_cast<int>(map.bricks().size());
}
