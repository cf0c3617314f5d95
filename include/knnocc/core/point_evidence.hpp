// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PointEvidence: what a SLAM system knows about one map point beyond its position, carried per
// point of a keyframe (PLY vertex properties `found`, `visible`, `observations`, io/ply.hpp;
// examples/orbslam/knnocc_orbslam_export.hpp writes them from ORB-SLAM):
//   found         frames whose tracking matched the map point (ORB-SLAM MapPoint::mnFound)
//   visible       frames whose view contained it: in the image, within its scale range and
//                 viewing angle (ORB-SLAM MapPoint::mnVisible; found <= visible)
//   observations  keyframes holding it (ORB-SLAM MapPoint::GetObservations().size(); not
//                 Observations(), which counts a stereo observation twice)
// All three are the SLAM system's counts when the keyframe was written; 0 means unknown. A
// contextual sensor model (sensor/contextual_model.hpp) may use them; the others ignore them.

#include <cstdint>

namespace knnocc {

struct PointEvidence {
  std::uint32_t found = 0;
  std::uint32_t visible = 0;
  std::uint32_t observations = 0;

  /// Whether the SLAM system gave a found/visible ratio for the point.
  bool has_ratio() const { return visible > 0 && found <= visible; }
};

}  // namespace knnocc
