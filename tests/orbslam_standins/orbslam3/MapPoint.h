#pragma once
// Stand-in for ORB-SLAM3's MapPoint (1.0): world position as Eigen::Vector3f (GetWorldPos).
#include <Eigen/Core>

#include "../common/slam_objects.hpp"

namespace ORB_SLAM3 {
class MapPoint : public knnocc_standin::BasicMapPoint<Eigen::Vector3f> {
 public:
  using BasicMapPoint::BasicMapPoint;
};
}  // namespace ORB_SLAM3
