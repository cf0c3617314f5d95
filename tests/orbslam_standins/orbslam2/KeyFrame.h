#pragma once
// Stand-in for ORB-SLAM2's KeyFrame: poses as 4x4 CV_32F cv::Mat (GetPose: Tcw, GetPoseInverse:
// Twc), map points by feature index (GetMapPointMatches).
#include "MapPoint.h"

namespace cv {
/// [R^T | -R^T t] of a rigid 4x4 transform.
inline Mat inverse(const Mat& T) {
  Mat inv(4, 4, CV_32F);
  for (int r = 0; r < 3; ++r) {
    float t = 0;
    for (int c = 0; c < 3; ++c) {
      inv.at<float>(r, c) = T.at<float>(c, r);
      t -= T.at<float>(c, r) * T.at<float>(c, 3);
    }
    inv.at<float>(r, 3) = t;
  }
  inv.at<float>(3, 3) = 1.0f;
  return inv;
}
}  // namespace cv

namespace ORB_SLAM2 {
class KeyFrame : public knnocc_standin::BasicKeyFrame<cv::Mat, MapPoint> {
 public:
  using BasicKeyFrame::BasicKeyFrame;
};
}  // namespace ORB_SLAM2
