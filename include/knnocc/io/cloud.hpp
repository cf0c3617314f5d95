#pragma once
// The in-memory point cloud every reader in knnocc::io returns.

#include <cstdint>
#include <vector>

#include "../core/point3.hpp"  // knnocc::Point3f

namespace knnocc::io {

struct Cloud {
  std::vector<Point3f> points;
  // One id per point when the file carries an id property (e.g. ORB-SLAM map-point ids);
  // empty otherwise.
  std::vector<std::uint64_t> ids;
};

}  // namespace knnocc::io
