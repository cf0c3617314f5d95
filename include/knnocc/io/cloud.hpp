// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The in-memory point cloud every reader in knnocc::io returns.

#include <cmath>
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
  // Whether the file's format declares an id property (a PLY vertex `id`, a PCD field `id`), so
  // that a cloud of zero points still says whether its keyframe carries ids.
  bool ids_declared = false;

  /// The cloud carries map-point ids: the format declares them (even for zero points), or ids
  /// are set. Ids are a property of the format, not of the point count.
  bool has_ids() const { return ids_declared || !ids.empty(); }
};

/// Drops the points farther than `crop` from the sensor (the cloud in the sensor frame; the
/// distance in double), with their ids, colours and SLAM counters: `knnocc map --crop`, the
/// paper's "keep points within 4 m". crop <= 0 (or NaN): nothing dropped.
inline void crop_cloud(Cloud& c, double crop) {
  if (!(crop > 0.0)) return;
  c.ids_declared = c.has_ids();  // a keyframe cropped to nothing still carries ids
  std::size_t kept = 0;
  for (std::size_t j = 0; j < c.points.size(); ++j) {
    const Point3f& p = c.points[j];
    if (!(std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z) <= crop)) continue;
    if (!c.ids.empty()) c.ids[kept] = c.ids[j];
    if (!c.colors.empty()) c.colors[kept] = c.colors[j];
    if (!c.evidence.empty()) c.evidence[kept] = c.evidence[j];
    c.points[kept++] = p;
  }
  c.points.resize(kept);
  if (!c.ids.empty()) c.ids.resize(kept);
  if (!c.colors.empty()) c.colors.resize(kept);
  if (!c.evidence.empty()) c.evidence.resize(kept);
}

}  // namespace knnocc::io
