// A simulated ORB-SLAM run, through the stand-in headers of ORB-SLAM2 (cv::Mat) or ORB-SLAM3
// (Sophus) chosen by KNNOCC_ORBSLAM (2 or 3), exported by examples/orbslam's KeyframeExporter
// as ORB-SLAM would drive it: a camera circles in a room (ORB-SLAM's world: the first camera,
// x right, y down, z forward), its pose estimate drifts in yaw, keyframe 30 closes the loop
// (every keyframe and map point corrected, the map's big-change index raised), a global BA
// then nudges every keyframe again, one keyframe is culled and some map points go bad.
//
// usage: simulate_run DIR     (prints "keyframes N snapshots M")

#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <mutex>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "Map.h"
#include "knnocc_orbslam_export.hpp"

#if KNNOCC_ORBSLAM == 2
namespace slam = ORB_SLAM2;
using SlamPose = cv::Mat;
SlamPose to_slam(const Eigen::Isometry3d& T) {
  cv::Mat m(4, 4, CV_32F);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m.at<float>(r, c) = static_cast<float>(T.matrix()(r, c));
  return m;
}
cv::Mat to_slam(const Eigen::Vector3d& p) {
  cv::Mat m(3, 1, CV_32F);
  for (int i = 0; i < 3; ++i) m.at<float>(i) = static_cast<float>(p(i));
  return m;
}
#else
namespace slam = ORB_SLAM3;
using SlamPose = Sophus::SE3f;
SlamPose to_slam(const Eigen::Isometry3d& T) {
  return Sophus::SE3f(T.rotation().cast<float>(), T.translation().cast<float>());
}
Eigen::Vector3f to_slam(const Eigen::Vector3d& p) { return p.cast<float>(); }
#endif

namespace {

constexpr int kKeyframes = 40, kLoopAt = 30, kCulled = 12;

// Camera to world of keyframe i on a circle of radius 1.5 m around (0, 0, 2), looking outwards,
// with `drift` radians of yaw error that grow along the path.
Eigen::Isometry3d camera_pose(int i, double drift) {
  const double a = 2.0 * M_PI * i / kLoopAt;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.5 * std::sin(a), 0.0, 2.0 - 1.5 * std::cos(a));
  T.linear() = Eigen::AngleAxisd(a + drift, Eigen::Vector3d::UnitY()).toRotationMatrix() *
               Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return T;
}

// Points on the walls (x = +-3, z = -1 and 5), floor (y = 1.2) and ceiling (y = -1.3).
std::vector<Eigen::Vector3d> room_points(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 3000; ++i) {
    const double s = u(rng), t = u(rng);
    switch (i % 6) {
      case 0:
        pts.emplace_back(-3.0, -1.3 + 2.5 * s, -1.0 + 6.0 * t);
        break;
      case 1:
        pts.emplace_back(3.0, -1.3 + 2.5 * s, -1.0 + 6.0 * t);
        break;
      case 2:
        pts.emplace_back(-3.0 + 6.0 * s, -1.3 + 2.5 * t, -1.0);
        break;
      case 3:
        pts.emplace_back(-3.0 + 6.0 * s, -1.3 + 2.5 * t, 5.0);
        break;
      case 4:
        pts.emplace_back(-3.0 + 6.0 * s, 1.2, -1.0 + 6.0 * t);
        break;
      default:
        pts.emplace_back(-3.0 + 6.0 * s, -1.3, -1.0 + 6.0 * t);
        break;
    }
  }
  return pts;
}

struct Run {
  slam::Map map;
  std::vector<std::unique_ptr<slam::KeyFrame>> keyframes;
  std::vector<std::unique_ptr<slam::MapPoint>> points;  // null until a keyframe creates it
  std::vector<Eigen::Vector3d> truth;
  std::vector<double> drift;  // per keyframe, radians

  // Keyframe i: sees the points in front of it within 5 m; creates the ones not seen before at
  // the position its drifted pose gives them.
  void add_keyframe(int i, std::mt19937& rng) {
    drift.push_back(i <= kLoopAt ? 0.004 * i : 0.0);
    const Eigen::Isometry3d est = camera_pose(i, drift.back()), gt = camera_pose(i, 0.0);
    std::unique_ptr<slam::KeyFrame> kf(new slam::KeyFrame(i, 100.0 + 0.5 * i, truth.size()));
    kf->SetPose(to_slam(est.inverse()));
    std::bernoulli_distribution found(0.8);
    for (std::size_t j = 0; j < truth.size(); ++j) {
      const Eigen::Vector3d c = gt.inverse() * truth[j];
      if (!(c.z() > 0.3 && c.norm() < 5.0 && std::abs(c.x()) < c.z() && std::abs(c.y()) < c.z()))
        continue;
      if (!points[j]) points[j].reset(new slam::MapPoint(to_slam(est * c), j));
      slam::MapPoint& mp = *points[j];
      mp.AddObservation(kf.get(), j, /*stereo=*/true);
      mp.IncreaseVisible(2);
      mp.IncreaseFound(found(rng) ? 2 : 1);
      kf->AddMapPoint(&mp, j);
    }
    map.AddKeyFrame(kf.get());
    keyframes.push_back(std::move(kf));
  }

  // Loop closing (or a global BA): every keyframe and map point moved, the big change reported.
  void correct(double yaw_error) {
    std::unique_lock<std::mutex> lock(map.mMutexMapUpdate);
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      drift[i] = yaw_error * static_cast<double>(i) / kKeyframes;
      keyframes[i]->SetPose(to_slam(camera_pose(static_cast<int>(i), drift[i]).inverse()));
    }
    for (std::size_t j = 0; j < points.size(); ++j)
      if (points[j]) points[j]->SetWorldPos(to_slam(truth[j]));
    map.InformNewBigChange();
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: simulate_run DIR\n");
    return 2;
  }
  try {
    std::mt19937 rng(35);
    Run run;
    run.truth = room_points(rng);
    run.points.resize(run.truth.size());
    knnocc::orbslam::KeyframeExporter exporter(argv[1]);
    for (int i = 0; i < kKeyframes; ++i) {
      run.add_keyframe(i, rng);
      if (i == kLoopAt) run.correct(0.0);
      if (i == kLoopAt + 4) run.correct(0.01);  // the global BA after the loop closure
      if (i == kCulled + 8) {                   // written by now; culled by local mapping
        run.keyframes[kCulled]->SetBadFlag();
        run.map.EraseKeyFrame(run.keyframes[kCulled].get());
        for (auto& mp : run.points)  // the first map point created
          if (mp) {
            mp->SetBadFlag();
            break;
          }
      }
      exporter.update(&run.map);
    }
    exporter.finish(&run.map);
    std::printf("keyframes %zu snapshots %zu\n", exporter.keyframes(), exporter.snapshots());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "simulate_run: %s\n", e.what());
    return 2;
  }
}
