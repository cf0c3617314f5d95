#pragma once
// Stand-in for ORB-SLAM3's KeyFrame (1.0): poses as Sophus::SE3f (GetPose: Tcw, GetPoseInverse:
// Twc), map points by feature index (GetMapPointMatches).
#include <sophus/se3.hpp>

#include "MapPoint.h"

namespace ORB_SLAM3 {
class KeyFrame : public knnocc_standin::BasicKeyFrame<Sophus::SE3f, MapPoint> {
 public:
  using BasicKeyFrame::BasicKeyFrame;
};
}  // namespace ORB_SLAM3
