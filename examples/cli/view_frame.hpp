#pragma once
// Which way is up in a map: pictures and the 3D page draw "up" along one of the six axis
// directions. Without --up it is taken from the sensor poses: for camera clouds (x right, y down,
// z forward: ORB-SLAM, TUM, the simulated stereo keyframes) the camera's -y, for LiDAR clouds the
// sensor's +z, averaged over the trajectory and rounded to the nearest axis direction.

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include <knnocc/io/cloud.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/map/occupancy_grid_2d.hpp>

#include "args.hpp"

namespace knnocc::cli {

/// An axis direction: axis 0, 1, 2 (x, y, z) and sign +1 or -1.
struct UpAxis {
  int axis = 2;
  int sign = 1;
  std::string name() const { return std::string(sign < 0 ? "-" : "") + char('x' + axis); }
  bool operator==(const UpAxis& o) const { return axis == o.axis && sign == o.sign; }
};

/// Parses x, y, z, -x, -y, -z (also +x ...); UsageError naming `flag` otherwise.
inline UpAxis parse_up_axis(const std::string& s, const std::string& flag = "--up") {
  std::string a = s;
  int sign = 1;
  if (!a.empty() && (a[0] == '-' || a[0] == '+')) {
    sign = a[0] == '-' ? -1 : 1;
    a = a.substr(1);
  }
  if (a.size() != 1 || a[0] < 'x' || a[0] > 'z')
    throw UsageError(flag + " must be x, y, z, -x, -y or -z, got '" + s + "'");
  return UpAxis{a[0] - 'x', sign};
}

/// Display axes of a map: right, forward and up as signed map axes (a right-handed frame with
/// up = the given direction). Display coordinate d of key index k along display axis i is
/// sign[i] * k[axis[i]].
struct ViewFrame {
  std::array<int, 3> axis{0, 1, 2};  // right, forward, up
  std::array<int, 3> sign{1, 1, 1};
  UpAxis up;

  explicit ViewFrame(UpAxis u = {}) : up(u) {
    const PlaneFrame f = PlaneFrame::with_up(u.axis, u.sign);
    axis = f.axis;
    sign = f.sign;
  }
};

/// Averages the "up" of sensor poses (sensor to world) and rounds it to an axis direction.
class UpEstimator {
 public:
  /// `sensor_points`: the cloud in the sensor frame, used to tell cameras from LiDARs (a camera
  /// sees only points in front, z > 0).
  void add(const io::Pose& pose, const std::vector<Point3f>& sensor_points) {
    std::size_t front = 0;
    for (const Point3f& p : sensor_points) front += p.z > 0.0f;
    const bool camera = !sensor_points.empty() && front * 100 >= sensor_points.size() * 95;
    const Eigen::Vector3d up_sensor = camera ? Eigen::Vector3d(0, -1, 0) : Eigen::Vector3d(0, 0, 1);
    sum_ += pose.q.toRotationMatrix() * up_sensor;
    ++n_;
  }
  bool empty() const { return n_ == 0; }
  /// The nearest axis direction to the mean up; z without poses.
  UpAxis result() const {
    if (n_ == 0 || sum_.norm() == 0.0) return {};
    int best = 0;
    for (int a = 1; a < 3; ++a)
      if (std::abs(sum_[a]) > std::abs(sum_[best])) best = a;
    return UpAxis{best, sum_[best] < 0 ? -1 : 1};
  }

 private:
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
  std::size_t n_ = 0;
};

}  // namespace knnocc::cli
