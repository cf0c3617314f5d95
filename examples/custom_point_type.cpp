// Using your own point type: public x, y, z members just work; anything else needs one
// specialisation of knnocc::point_traits.
#include <cstdio>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>

struct LidarReturn {  // has x, y, z: usable as is
  float x, y, z;
  float intensity;
};

struct PackedPoint {  // no x, y, z members: tell knnocc how to read it
  double xyz[3];
};

template <>
struct knnocc::point_traits<PackedPoint> {
  static constexpr bool is_specialised = true;
  static double x(const PackedPoint& p) { return p.xyz[0]; }
  static double y(const PackedPoint& p) { return p.xyz[1]; }
  static double z(const PackedPoint& p) { return p.xyz[2]; }
};

int main() {
  knnocc::OccupancyMap<> map(0.05);
  const std::vector<LidarReturn> a = {{1.0f, 1.0f, 0.2f, 0.7f}};
  const std::vector<PackedPoint> b = {{{-1.0, 0.5, 0.2}}};
  knnocc::insert_point_cloud(map, PackedPoint{{0, 0, 0}}, a);
  knnocc::insert_point_cloud(map, LidarReturn{0, 0, 0, 0}, b);
  const auto c = map.count_voxels();
  std::printf("occupied %zu free %zu\n", c.occupied, c.free);
  return 0;
}
