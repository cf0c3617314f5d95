#pragma once
// Stand-in for ORB-SLAM2's Map: GetAllKeyFrames, GetLastBigChangeIdx, mMutexMapUpdate.
#include "KeyFrame.h"

namespace ORB_SLAM2 {
class Map : public knnocc_standin::BasicMap<KeyFrame> {};
}  // namespace ORB_SLAM2
