// The smallest complete use of knnocc: insert one scan with OctoMap's model and query the map.
#include <cstdio>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

int main() {
  knnocc::OccupancyMap<> map(0.1);  // 0.1 m voxels, OctoMap's clamping defaults
  const std::vector<knnocc::Point3f> scan = {{2.0f, 0.0f, 0.0f}, {2.0f, 0.5f, 0.1f}};
  const knnocc::ScanStats st = knnocc::insert_point_cloud(map, knnocc::Point3f{0, 0, 0}, scan);

  knnocc::OcKey key;
  map.grid().coord_to_key(2.0, 0.0, 0.0, key);
  const auto v = map.logodds(key);  // nullopt when unknown
  std::printf("%zu voxels freed, %zu occupied; voxel at (2,0,0): log-odds %.4f, occupied %s\n",
              st.free_voxels, st.occupied_voxels, v ? *v : 0.0f,
              v && map.is_occupied(*v) ? "yes" : "no");
  return 0;
}
