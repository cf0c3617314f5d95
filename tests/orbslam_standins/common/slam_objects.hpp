#pragma once
// The parts of ORB-SLAM's MapPoint, KeyFrame and Map that the keyframe exporter
// (examples/orbslam/knnocc_orbslam_export.hpp) calls, with ORB-SLAM's names and signatures,
// written once for both APIs: ORB-SLAM2 instantiates them with cv::Mat poses and positions,
// ORB-SLAM3 with Sophus::SE3f and Eigen::Vector3f (orbslam2/, orbslam3/). Stand-ins for the
// exporter's test, not ORB-SLAM.

#include <cstddef>
#include <map>
#include <mutex>
#include <set>
#include <vector>

namespace knnocc_standin {

// A value's deep copy and a pose's inverse; an API with other semantics (cv::Mat copies share
// their data) overloads them in its types' namespace.
template <class T>
T copy_of(const T& v) {
  return v;
}
template <class T>
auto inverse(const T& pose) -> decltype(pose.inverse()) {
  return pose.inverse();
}

template <class Position>
class BasicMapPoint {
 public:
  BasicMapPoint(const Position& Pos, long unsigned int id) : mnId(id), mWorldPos(copy_of(Pos)) {}

  void SetWorldPos(const Position& Pos) {
    std::unique_lock<std::mutex> lock(mMutexPos);
    mWorldPos = copy_of(Pos);
  }
  Position GetWorldPos() {
    std::unique_lock<std::mutex> lock(mMutexPos);
    return copy_of(mWorldPos);
  }
  // ORB-SLAM: nObs counts a stereo observation twice; GetObservations() holds one entry per
  // keyframe (ORB-SLAM2: std::map<KeyFrame*, size_t>; ORB-SLAM3's value is a tuple of indices).
  int Observations() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    return nObs;
  }
  std::map<const void*, std::size_t> GetObservations() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    return mObservations;
  }
  void AddObservation(const void* pKF, std::size_t idx, bool stereo) {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    if (!mObservations.emplace(pKF, idx).second) return;
    nObs += stereo ? 2 : 1;
  }
  void SetBadFlag() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    mbBad = true;
  }
  bool isBad() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    return mbBad;
  }
  void IncreaseVisible(int n = 1) {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    mnVisible += n;
  }
  void IncreaseFound(int n = 1) {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    mnFound += n;
  }
  float GetFoundRatio() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    return static_cast<float>(mnFound) / mnVisible;
  }
  inline int GetFound() { return mnFound; }

  long unsigned int mnId;
  int nObs = 0;

 protected:
  Position mWorldPos;
  int mnVisible = 1;
  int mnFound = 1;
  bool mbBad = false;
  std::map<const void*, std::size_t> mObservations;
  std::mutex mMutexPos;
  std::mutex mMutexFeatures;
};

/// Pose: world to camera (Tcw), as SetPose takes it; GetPoseInverse gives camera to world.
template <class Pose, class MapPoint>
class BasicKeyFrame {
 public:
  BasicKeyFrame(long unsigned int id, double stamp, std::size_t features)
      : mnId(id), mTimeStamp(stamp), mvpMapPoints(features, nullptr) {}

  void SetPose(const Pose& Tcw_) {
    std::unique_lock<std::mutex> lock(mMutexPose);
    Tcw = copy_of(Tcw_);
    Twc = inverse(Tcw_);
  }
  Pose GetPose() {
    std::unique_lock<std::mutex> lock(mMutexPose);
    return copy_of(Tcw);
  }
  Pose GetPoseInverse() {
    std::unique_lock<std::mutex> lock(mMutexPose);
    return copy_of(Twc);
  }
  void AddMapPoint(MapPoint* pMP, const std::size_t& idx) {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    mvpMapPoints[idx] = pMP;
  }
  std::vector<MapPoint*> GetMapPointMatches() {
    std::unique_lock<std::mutex> lock(mMutexFeatures);
    return mvpMapPoints;
  }
  void SetBadFlag() {
    std::unique_lock<std::mutex> lock(mMutexConnections);
    mbBad = true;
  }
  bool isBad() {
    std::unique_lock<std::mutex> lock(mMutexConnections);
    return mbBad;
  }

  long unsigned int mnId;
  const double mTimeStamp;

 protected:
  Pose Tcw, Twc;
  std::vector<MapPoint*> mvpMapPoints;
  bool mbBad = false;
  std::mutex mMutexPose, mMutexConnections, mMutexFeatures;
};

template <class KeyFrame>
class BasicMap {
 public:
  void AddKeyFrame(KeyFrame* pKF) {
    std::unique_lock<std::mutex> lock(mMutexMap);
    mspKeyFrames.insert(pKF);
  }
  void EraseKeyFrame(KeyFrame* pKF) {
    std::unique_lock<std::mutex> lock(mMutexMap);
    mspKeyFrames.erase(pKF);
  }
  void InformNewBigChange() {
    std::unique_lock<std::mutex> lock(mMutexMap);
    mnBigChangeIdx++;
  }
  int GetLastBigChangeIdx() {
    std::unique_lock<std::mutex> lock(mMutexMap);
    return mnBigChangeIdx;
  }
  std::vector<KeyFrame*> GetAllKeyFrames() {
    std::unique_lock<std::mutex> lock(mMutexMap);
    return std::vector<KeyFrame*>(mspKeyFrames.begin(), mspKeyFrames.end());
  }

  std::mutex mMutexMapUpdate;

 protected:
  std::set<KeyFrame*> mspKeyFrames;
  int mnBigChangeIdx = 0;
  std::mutex mMutexMap;
};

}  // namespace knnocc_standin
