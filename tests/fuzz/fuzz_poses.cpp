// Trajectory reader (stamp tx ty tz qx qy qz qw): every accepted pose is finite and unit.
#include <cmath>

#include <knnocc/io/trajectory.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  knnocc::fuzz::read_rejecting_cleanly(data, size, ".txt", [](const std::string& p) {
    for (const knnocc::io::Pose& pose : knnocc::io::read_poses(p))
      if (!pose.t.allFinite() || !(std::fabs(pose.q.norm() - 1.0) < 1e-9)) std::abort();
  });
  return 0;
}
