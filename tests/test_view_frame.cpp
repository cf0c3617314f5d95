// The up axis of pictures and view pages: parsing, the display frame for each of the six
// directions, and the estimate from sensor poses (cameras: -y of the camera, LiDARs: +z).

#include <doctest/doctest.h>

#ifdef KNNOCC_TEST_TOOL_HEADERS
#include "view_frame.hpp"

using namespace knnocc;

TEST_CASE("view_frame.parse and right-handed frames") {
  CHECK(cli::parse_up_axis("z") == cli::UpAxis{2, 1});
  CHECK(cli::parse_up_axis("-y") == cli::UpAxis{1, -1});
  CHECK(cli::parse_up_axis("+x") == cli::UpAxis{0, 1});
  CHECK_THROWS_WITH_AS(cli::parse_up_axis("w"), doctest::Contains("--up must be x, y, z"),
                       cli::UsageError);
  CHECK_THROWS_AS(cli::parse_up_axis("-"), cli::UsageError);
  CHECK_THROWS_AS(cli::parse_up_axis("zz"), cli::UsageError);
  for (int axis = 0; axis < 3; ++axis)
    for (int sign : {-1, 1}) {
      const cli::ViewFrame f(cli::UpAxis{axis, sign});
      Eigen::Vector3d e[3];
      for (int i = 0; i < 3; ++i) {
        e[i] = Eigen::Vector3d::Zero();
        e[i][f.axis[i]] = f.sign[i];
      }
      CAPTURE(axis);
      CAPTURE(sign);
      CHECK(e[2][axis] == sign);               // up is the given direction
      CHECK(e[0].cross(e[1]).isApprox(e[2]));  // right x forward = up
    }
  // ORB-SLAM's first-camera frame: up -y, right x, forward +z.
  const cli::ViewFrame orb(cli::UpAxis{1, -1});
  CHECK(orb.axis[0] == 0);
  CHECK(orb.axis[1] == 2);
  CHECK(orb.sign[1] == 1);
}

TEST_CASE("view_frame.up from poses") {
  std::vector<Point3f> camera_cloud{{0.1f, 0.2f, 2.0f}, {-1.0f, 0.5f, 3.0f}, {0, 0, 1.0f}};
  std::vector<Point3f> lidar_cloud{{5, 0, -1}, {-5, 1, 0.5f}, {0, -4, -1.2f}, {2, 2, 1}};
  cli::UpEstimator none;
  CHECK(none.result() == cli::UpAxis{2, 1});
  io::Pose identity;
  cli::UpEstimator orb;  // ORB-SLAM: the world is the first camera's frame
  orb.add(identity, camera_cloud);
  CHECK(orb.result() == cli::UpAxis{1, -1});
  cli::UpEstimator lidar;
  lidar.add(identity, lidar_cloud);
  CHECK(lidar.result() == cli::UpAxis{2, 1});
  // TUM / the simulated stereo camera: optical frame in a z-up world, looking level along +x:
  // camera z -> world x, camera x -> world -y, camera y -> world -z.
  io::Pose level;
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  level.q = Eigen::Quaterniond(R);
  cli::UpEstimator tum;
  for (int i = 0; i < 5; ++i) tum.add(level, camera_cloud);
  CHECK(tum.result() == cli::UpAxis{2, 1});
}
#endif
