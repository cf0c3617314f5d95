// KITTI inputs: velodyne .bin scans, calib.txt (Tr), and trajectories (TUM or KITTI 3x4,
// told apart by read_trajectory); the same bytes go to all three readers.
#include <cmath>

#include <knnocc/io/kitti.hpp>
#include <knnocc/io/trajectory.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".bin",
                                       [](const std::string& p) { knnocc::io::read_kitti_bin(p); });
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".calib", [](const std::string& p) {
    const Eigen::Isometry3d tr = knnocc::io::read_kitti_calib_tr(p);
    if (!tr.matrix().allFinite()) std::abort();
  });
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".poses", [](const std::string& p) {
    for (const knnocc::io::Pose& pose : knnocc::io::read_trajectory(p))
      if (!pose.t.allFinite() || !(std::fabs(pose.q.norm() - 1.0) < 1e-6)) std::abort();
  });
  return 0;
}
