#pragma once
// PointContext: what Mapper knows about one endpoint of a keyframe beyond its mean k-NN distance,
// for a rated sensor model that asks for it (sensor/sensor_model.hpp: `rate(const PointContext&,
// const RunningNormal&)`, e.g. RobustModel). Mapper gathers it only for such a model.

#include <cstddef>
#include <cstdint>
#include <limits>

namespace knnocc {

struct PointContext {
  double s = std::numeric_limits<double>::quiet_NaN();  ///< mean k-NN distance (NaN: none)
  /// Keyframes that have observed the endpoint's map point so far, this one included; 0 when
  /// the keyframes carry no map-point ids (every point a new map point).
  std::uint32_t views = 0;
  std::uint32_t in_voxel = 1;  ///< this keyframe's rated endpoints in the endpoint's voxel
  double range = 0.0;          ///< distance from the sensor (m)
  double parallax = 0.0;       ///< angle (rad) between this viewing ray and the first one's
  /// Keyframes from the map point's creator (its first observer) to this one (0: created here).
  std::size_t span = 0;
  /// The voxel's log-odds before this keyframe (NaN: unknown): free evidence other keyframes'
  /// rays left there.
  float voxel_logodds = std::numeric_limits<float>::quiet_NaN();
  std::size_t keyframe = 0;  ///< index of the keyframe (0 for the first)
  /// Other keyframes whose rays passed through the map point (insertion/map_point_ledger.hpp).
  std::uint32_t contradictions = 0;
  /// The map point has added occupied evidence before this keyframe.
  bool committed = false;
  /// The map point committed by the model's own rules for it before this keyframe (not only
  /// beside other points: RobustModelParams::near_views); the same as `committed` for a model
  /// without that rule.
  bool anchor = false;
  /// Anchors (map points with `anchor`) in the endpoint's voxel and the 26 around it; the
  /// largest value when not counted (sensor_model.hpp: wants_anchors).
  std::uint32_t anchors = std::numeric_limits<std::uint32_t>::max();
  /// Independent support: other map points within the model's support radius
  /// (sensor_model.hpp: support_radius) that a keyframe other than this point's creator (its
  /// first observer) created; the largest value when not counted (e.g. once an anchor).
  std::uint32_t support = std::numeric_limits<std::uint32_t>::max();
  /// The other map points within the same radius that its own creator created (counted with
  /// support; the largest value when not counted).
  std::uint32_t siblings = std::numeric_limits<std::uint32_t>::max();
};

}  // namespace knnocc
