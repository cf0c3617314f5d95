// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Odometry drift and its corrections, for simulating what a SLAM system reports while mapping:
//   the tracking estimate of keyframe i (what poses.txt holds when keyframes are written as they
//   are made) is the true pose rotated about the vertical axis through the first keyframe's
//   position by i * heading_drift, plus a small per-keyframe jitter (yaw and translation);
//   every `local_every` keyframes local bundle adjustment removes the jitter of the last
//   `local_window` keyframes (a snapshot with their drifted, jitter-free poses);
//   after the last keyframe the loop closes: a snapshot of every keyframe at its true pose.
// The snapshots are those of `knnocc map --corrections` (after_NNNNNN.txt, keyframes 0..NNNNNN),
// so the final corrected map must equal the map built from the true poses.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "../io/trajectory.hpp"

namespace knnocc::sim {

struct DriftParams {
  double heading_drift = 0.1 * M_PI / 180.0;  ///< rad per keyframe, accumulating
  double jitter_yaw = 0.2 * M_PI / 180.0;     ///< rad (sd), removed by local bundle adjustment
  double jitter_t = 0.01;                     ///< m (sd), removed by local bundle adjustment
  std::size_t local_every = 10;               ///< a local correction every N keyframes (0: none)
  std::size_t local_window = 5;               ///< keyframes it re-poses
  std::uint64_t seed = 1;
};

/// What a drifting SLAM run reports: the tracking estimates and the snapshots by keyframe index.
struct DriftedRun {
  std::vector<io::Pose> tracked;                           ///< poses.txt
  std::map<std::size_t, std::vector<io::Pose>> snapshots;  ///< after_NNNNNN.txt
  double max_offset = 0;  ///< m: the largest distance of a tracked position from the truth
};

namespace detail {
inline io::Pose yawed(const io::Pose& p, const Eigen::Vector3d& pivot, double angle,
                      const Eigen::Vector3d& shift) {
  const Eigen::AngleAxisd r(angle, Eigen::Vector3d::UnitZ());
  io::Pose out = p;
  out.t = r * (p.t - pivot) + pivot + shift;
  out.q = (Eigen::Quaterniond(r) * p.q).normalized();
  return out;
}
}  // namespace detail

inline DriftedRun drift_run(const std::vector<io::Pose>& truth, const DriftParams& dp) {
  DriftedRun run;
  if (truth.empty()) return run;
  std::mt19937_64 rng(dp.seed);
  auto normal = [&rng](double sd) {  // Box-Muller on the generator's bits: portable
    const double u1 = ((rng() >> 11) + 1) * 0x1.0p-53, u2 = (rng() >> 11) * 0x1.0p-53;
    return sd * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  };
  const Eigen::Vector3d pivot = truth.front().t;
  std::vector<io::Pose> drifted;  // without jitter
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double a = dp.heading_drift * static_cast<double>(i);
    drifted.push_back(detail::yawed(truth[i], pivot, a, Eigen::Vector3d::Zero()));
    const Eigen::Vector3d shift(normal(dp.jitter_t), normal(dp.jitter_t), 0.0);
    run.tracked.push_back(detail::yawed(drifted.back(), drifted.back().t,
                                        i == 0 ? 0.0 : normal(dp.jitter_yaw),
                                        i == 0 ? Eigen::Vector3d::Zero() : shift));
    run.max_offset = std::max(run.max_offset, (run.tracked.back().t - truth[i].t).norm());
  }
  std::vector<io::Pose> known = run.tracked;  // what the SLAM system knows so far
  for (std::size_t i = 0; i + 1 < truth.size(); ++i) {
    if (dp.local_every == 0 || (i + 1) % dp.local_every != 0) continue;
    for (std::size_t j = i + 1 > dp.local_window ? i + 1 - dp.local_window : 0; j <= i; ++j)
      known[j] = drifted[j];
    run.snapshots[i] = std::vector<io::Pose>(known.begin(), known.begin() + long(i + 1));
  }
  run.snapshots[truth.size() - 1] = truth;  // the loop closes
  return run;
}

}  // namespace knnocc::sim
