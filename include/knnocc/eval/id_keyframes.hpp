// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A sequence's keyframes as the held-out evaluation takes them (eval/heldout.hpp's IdKeyframe):
// each keyframe's sensor position and its points in the world frame with their map-point ids,
// and the SLAM system's counters when the clouds carry them.
//
// Thread safety: a function of its arguments (it reads the sequence's files).

#include <cstddef>
#include <vector>

#include "../io/error.hpp"
#include "../io/sequence.hpp"
#include "heldout.hpp"

namespace knnocc::eval {

/// The keyframes of `seq`, points farther than crop (> 0) from their sensor dropped;
/// io::Error naming the cloud when one has no map-point ids (an `id` vertex property).
/// check(i, cloud), when given, sees each whole cloud first (a caller's own checks).
template <class Check>
std::vector<IdKeyframe> id_keyframes(const io::Sequence& seq, double crop, Check&& check) {
  std::vector<IdKeyframe> out(seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud cloud = seq.load_cloud(i);
    if (!cloud.has_ids())
      throw io::Error(seq.cloud_path(i), "no map-point ids (an `id` vertex property)");
    check(i, cloud);
    io::keyframe_to_world(seq.pose(i), cloud, crop, out[i].points, out[i].ids, &out[i].evidence);
    const Eigen::Vector3d& t = seq.pose(i).t;
    out[i].origin = {t.x(), t.y(), t.z()};
  }
  return out;
}

inline std::vector<IdKeyframe> id_keyframes(const io::Sequence& seq, double crop) {
  return id_keyframes(seq, crop, [](std::size_t, const io::Cloud&) {});
}

}  // namespace knnocc::eval
