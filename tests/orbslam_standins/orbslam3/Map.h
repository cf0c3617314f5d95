#pragma once
// Stand-in for ORB-SLAM3's Map: GetAllKeyFrames, GetLastBigChangeIdx, mMutexMapUpdate.
#include "KeyFrame.h"

namespace ORB_SLAM3 {
class Map : public knnocc_standin::BasicMap<KeyFrame> {};
}  // namespace ORB_SLAM3
