#pragma once
// Stand-in for ORB-SLAM2's MapPoint: world position as a 3x1 CV_32F cv::Mat (GetWorldPos).
#include <opencv2/core/core.hpp>

namespace cv {
inline Mat copy_of(const Mat& m) { return m.clone(); }
}  // namespace cv

#include "../common/slam_objects.hpp"

namespace ORB_SLAM2 {
class MapPoint : public knnocc_standin::BasicMapPoint<cv::Mat> {
 public:
  using BasicMapPoint::BasicMapPoint;
};
}  // namespace ORB_SLAM2
