// Downstream test of knnocc::core alone: a map, the scan integrator, the OctoMap model through
// Mapper, a ray query and Welford's statistics, with neither nanoflann nor Eigen.
#include <knnocc/core/point3.hpp>
#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/raycast/cast_ray.hpp>
#include <knnocc/sensor/octomap_model.hpp>
#include <knnocc/stats/welford.hpp>
#include <knnocc/version.hpp>

#include <iostream>
#include <vector>

int main() {
  std::vector<knnocc::Point3f> wall;
  for (int i = -10; i <= 10; ++i)
    for (int j = -10; j <= 10; ++j) wall.push_back({2.0f, 0.05f * i, 0.05f * j});
  knnocc::Mapper<knnocc::OctoMapModel> mapper(0.1);
  mapper.insert_keyframe(knnocc::Point3f{0, 0, 0}, wall);
  const auto counts = mapper.map().count_voxels();
  const auto hit = knnocc::cast_ray(mapper.map(), knnocc::Point3f{0, 0, 0},
                                    knnocc::Point3f{1, 0, 0}, false, 10.0);
  knnocc::RunningNormal stats;
  stats.add(1.0);
  stats.add(3.0);
  if (counts.occupied == 0 || counts.free == 0 || !hit.hit() || stats.mean() != 2.0) {
    std::cerr << "unexpected map: occupied " << counts.occupied << " free " << counts.free << '\n';
    return 1;
  }
  std::cout << "knnocc " << knnocc::version_string << " core: occupied " << counts.occupied
            << " free " << counts.free << '\n';
  return 0;
}
