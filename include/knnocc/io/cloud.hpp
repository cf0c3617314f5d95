// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The in-memory point cloud every reader in knnocc::io returns.

#include <cstdint>
#include <vector>

#include "../core/point3.hpp"          // knnocc::Point3f
#include "../core/point_evidence.hpp"  // knnocc::PointEvidence
#include "../core/rgb.hpp"             // knnocc::Rgb

namespace knnocc::io {

struct Cloud {
  std::vector<Point3f> points;
  // One id per point when the file carries an id property (e.g. ORB-SLAM map-point ids);
  // empty otherwise.
  std::vector<std::uint64_t> ids;
  // One colour per point when the file carries one (PLY uchar red, green, blue; PCD rgb or
  // rgba); empty otherwise.
  std::vector<Rgb> colors;
  // One per point when the file carries any of the SLAM counters `found`, `visible`,
  // `observations` (PLY vertex properties, core/point_evidence.hpp; absent ones read 0); empty
  // otherwise.
  std::vector<PointEvidence> evidence;
};

}  // namespace knnocc::io
