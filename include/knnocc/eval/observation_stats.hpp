// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// How a sequence's map points are observed: the statistics the simulator is calibrated on
// (docs/evaluation.md, "Simulator calibration"), for any sequence whose points carry map-point
// ids (ORB-SLAM keyframes, `knnocc sim`):
//
//   views       keyframes that observe a map point (an id counts once per keyframe)
//   span        last - first index of the keyframes that observe it
//   detection   views / the keyframes whose view contains the point (observers always count)
//
// "Whose view contains it" is estimated from the data alone, never from a camera model or a
// simulator parameter (estimate_view):
//   field of view  the [q, 1 - q] quantiles (q = 0.5 %) of every observation's horizontal and
//                  vertical angle in its camera frame, atan2(x, z) and atan2(y, z) (camera x right,
//                  y down, z forward), pooled over the sequence: the camera is one;
//   range          per keyframe, the least and the greatest distance of its own observations
//                  from its sensor (what that keyframe could resolve: near and far limits move
//                  with the scene).
// A point is in keyframe i's view when it lies in front of it (z > 0), inside the field of view
// and within i's range. Occlusion is not modelled, so views that "should have seen" a point are
// over-counted and detection rates are lower bounds. A map point's position is its first
// observation's (ORB-SLAM map points have one position).
//
// Thread safety: functions of their arguments only.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "../core/point3.hpp"

namespace knnocc::eval {

/// One keyframe: its camera pose and its points (world frame), one map-point id each.
struct ObservedKeyframe {
  Point3d origin;
  /// Camera to world rotation, row-major: column c is camera axis c in the world.
  std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::vector<Point3d> points;
  std::vector<std::uint64_t> ids;

  /// p (world) in this keyframe's camera frame.
  Point3d to_camera(const Point3d& p) const {
    const double d[3] = {p.x - origin.x, p.y - origin.y, p.z - origin.z};
    const auto& r = rotation;
    return {r[0] * d[0] + r[3] * d[1] + r[6] * d[2], r[1] * d[0] + r[4] * d[1] + r[7] * d[2],
            r[2] * d[0] + r[5] * d[1] + r[8] * d[2]};
  }
};

/// The view estimated from the sequence's own observations.
struct ViewModel {
  double h_lo = 0, h_hi = 0, v_lo = 0, v_hi = 0;  ///< angle bounds (rad), x/z and y/z
  std::vector<double> r_lo, r_hi;                 ///< per keyframe: range of its observations
  std::size_t behind = 0;  ///< observations with z <= 0 (left out of the angles)

  /// Is world point p in keyframe i's view?
  bool contains(const ObservedKeyframe& kf, std::size_t i, const Point3d& p) const {
    const Point3d c = kf.to_camera(p);
    if (!(c.z > 0)) return false;
    const double h = std::atan2(c.x, c.z), v = std::atan2(c.y, c.z);
    if (h < h_lo || h > h_hi || v < v_lo || v > v_hi) return false;
    const double r = std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    return r >= r_lo[i] && r <= r_hi[i];
  }
};

namespace detail {
/// The q-quantile of v (nearest rank on the sorted values; v is reordered); 0 when empty.
inline double quantile(std::vector<double>& v, double q) {
  if (v.empty()) return 0.0;
  const auto n = static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(std::llround(q * n));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
  return v[i];
}
}  // namespace detail

/// The field of view ([q, 1 - q] quantiles of the angles) and each keyframe's range.
inline ViewModel estimate_view(const std::vector<ObservedKeyframe>& kfs, double q = 0.005) {
  ViewModel m;
  std::vector<double> h, v;
  for (const ObservedKeyframe& kf : kfs) {
    double lo = INFINITY, hi = -INFINITY;
    for (const Point3d& p : kf.points) {
      const Point3d c = kf.to_camera(p);
      const double r = std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
      lo = std::min(lo, r);
      hi = std::max(hi, r);
      if (!(c.z > 0)) {
        ++m.behind;
        continue;
      }
      h.push_back(std::atan2(c.x, c.z));
      v.push_back(std::atan2(c.y, c.z));
    }
    m.r_lo.push_back(lo);
    m.r_hi.push_back(hi);
  }
  m.h_lo = detail::quantile(h, q);
  m.h_hi = detail::quantile(h, 1 - q);
  m.v_lo = detail::quantile(v, q);
  m.v_hi = detail::quantile(v, 1 - q);
  return m;
}

/// One map point's observations.
struct PointObservations {
  std::uint64_t id = 0;
  Point3d position;           ///< at its first observation
  std::uint32_t views = 0;    ///< keyframes that observe it
  std::uint32_t first = 0;    ///< index of the first of them
  std::uint32_t last = 0;     ///< index of the last
  std::uint32_t in_view = 0;  ///< keyframes whose view contains it, or that observe it
  std::uint32_t span() const { return last - first; }
  double detection() const { return in_view ? double(views) / double(in_view) : 0.0; }
};

/// Every map point's views, span and the keyframes whose view contains it, in order of first
/// observation.
inline std::vector<PointObservations> observe_points(const std::vector<ObservedKeyframe>& kfs,
                                                     const ViewModel& view) {
  std::vector<PointObservations> pts;
  std::unordered_map<std::uint64_t, std::size_t> index;
  std::vector<std::uint32_t> last_seen;  // per point: keyframe index + 1 that counted it
  for (std::size_t i = 0; i < kfs.size(); ++i) {
    const ObservedKeyframe& kf = kfs[i];
    for (std::size_t j = 0; j < kf.points.size() && j < kf.ids.size(); ++j) {
      const auto [it, fresh] = index.try_emplace(kf.ids[j], pts.size());
      if (fresh) {
        PointObservations o;
        o.id = kf.ids[j];
        o.position = kf.points[j];
        o.first = static_cast<std::uint32_t>(i);
        pts.push_back(o);
        last_seen.push_back(0);
      }
      const std::size_t k = it->second;
      if (last_seen[k] == i + 1) continue;  // an id counts once per keyframe
      last_seen[k] = static_cast<std::uint32_t>(i + 1);
      ++pts[k].views;
      pts[k].last = static_cast<std::uint32_t>(i);
    }
  }
  for (std::size_t k = 0; k < pts.size(); ++k)
    for (std::size_t i = 0; i < kfs.size(); ++i)
      pts[k].in_view += view.contains(kfs[i], i, pts[k].position);
  // Observers count even where the estimated view leaves them out (angles beyond the quantiles).
  std::vector<std::uint32_t> observed_outside(pts.size(), 0);
  std::fill(last_seen.begin(), last_seen.end(), 0);
  for (std::size_t i = 0; i < kfs.size(); ++i) {
    const ObservedKeyframe& kf = kfs[i];
    for (std::size_t j = 0; j < kf.points.size() && j < kf.ids.size(); ++j) {
      const std::size_t k = index.at(kf.ids[j]);
      if (last_seen[k] == i + 1) continue;
      last_seen[k] = static_cast<std::uint32_t>(i + 1);
      observed_outside[k] += !view.contains(kf, i, pts[k].position);
    }
  }
  for (std::size_t k = 0; k < pts.size(); ++k) pts[k].in_view += observed_outside[k];
  return pts;
}

/// The distributions `knnocc eval --ids` prints.
struct ObservationSummary {
  std::size_t points = 0, multiview = 0;  ///< all map points; those with >= 2 views
  /// Share of the map points seen by 1, 2, 3, 4, 5, 6-10, 11-20 and more than 20 keyframes.
  std::array<double, 8> views{};
  double span_median = 0, span_p90 = 0;  ///< over the multi-view points
  double within5 = 0;  ///< multi-view points seen only within 5 consecutive keyframes (span <= 4)
  double detection_p10 = 0, detection_median = 0, detection_p90 = 0;  ///< over all points
  double detection_median_multiview = 0;
};

inline ObservationSummary summarize(const std::vector<PointObservations>& pts) {
  ObservationSummary s;
  s.points = pts.size();
  if (pts.empty()) return s;
  std::vector<double> span, det, det_mv;
  std::size_t within5 = 0;
  for (const PointObservations& p : pts) {
    const std::uint32_t v = p.views;
    const std::size_t bin = v <= 5 ? v - 1 : v <= 10 ? 5 : v <= 20 ? 6 : 7;
    s.views[bin] += 1;
    det.push_back(p.detection());
    if (v < 2) continue;
    ++s.multiview;
    span.push_back(p.span());
    det_mv.push_back(p.detection());
    within5 += p.span() <= 4;
  }
  for (double& b : s.views) b /= double(pts.size());
  s.span_median = detail::quantile(span, 0.5);
  s.span_p90 = detail::quantile(span, 0.9);
  s.within5 = s.multiview ? double(within5) / double(s.multiview) : 0.0;
  s.detection_p10 = detail::quantile(det, 0.1);
  s.detection_median = detail::quantile(det, 0.5);
  s.detection_p90 = detail::quantile(det, 0.9);
  s.detection_median_multiview = detail::quantile(det_mv, 0.5);
  return s;
}

}  // namespace knnocc::eval
