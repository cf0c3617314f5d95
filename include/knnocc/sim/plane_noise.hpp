// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// plane_fit_noise: a range-noise statistic of one scan in its sensor frame (sensor at the origin),
// measured the same way on a real scan and on a simulated one, so the simulator's noise can be
// calibrated on real data and checked against it (sim/drive_scene.hpp).
//
// Every `stride`-th point is the centre of a patch: the points within R = max(min_radius,
// radius_fraction * range) of it. A least-squares plane is fitted to the patch (the covariance's
// smallest eigenvector). Patches that are not a plane seen from the front are left out: fewer than
// min_points points, points along a line only (the middle eigenvalue's sd below R / 5), a curved
// or cluttered patch (smallest sd above max_flatness times the middle one) or a grazing view (the
// cosine between the plane's normal and the line of sight below min_cos). A kept patch's noise is
// its RMS residual (corrected for the three fitted parameters) divided by that cosine: what the
// spread along the beam must be for the spread across the plane. Per range bin (edges 0.5, 2, 4, 8,
// 16, 32, 80 m) the median over patches, which a few non-planar patches that pass the tests hardly
// move; the surfaces' own roughness stays in the number (real walls are not perfect planes).
//
// Thread safety: a pure function.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "../core/point3.hpp"

namespace knnocc::sim {

struct PlaneNoiseParams {
  double radius_fraction = 0.015;  ///< patch radius as a fraction of its centre's range
  double min_radius = 0.1;         ///< smallest patch radius (m)
  std::size_t min_points = 12;     ///< fewer points: no patch
  double min_cos = 0.5;            ///< the plane seen at most 60 degrees off its normal
  double max_flatness = 0.25;      ///< smallest over middle sd of the patch, at most
  std::size_t stride = 5;          ///< every stride-th point a patch centre
};

/// One range bin: patches whose centre lies in [lo, hi) m from the sensor.
struct PlaneNoiseBin {
  double lo = 0, hi = 0;
  std::size_t patches = 0;
  double median = 0;  ///< the median patch noise (m); 0 without patches
};

struct PlaneNoise {
  std::vector<PlaneNoiseBin> bins;
  std::size_t patches = 0;  ///< kept patches over all bins
  double median = 0;        ///< the median over all kept patches (m); 0 without any
};

namespace detail {

/// The range bins' edges (m).
inline constexpr double kPlaneNoiseEdges[] = {0.5, 2, 4, 8, 16, 32, 80};

inline double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

/// Points hashed into cubes of one edge, for the patches of one range bin.
class PatchGrid {
 public:
  PatchGrid(const std::vector<Point3f>& pts, double cell) : pts_(pts), inv_(1.0 / cell) {
    order_.resize(pts.size());
    std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i)
      keyed[i] = {key(cell_of(pts[i].x), cell_of(pts[i].y), cell_of(pts[i].z)),
                  static_cast<std::uint32_t>(i)};
    std::sort(keyed.begin(), keyed.end());
    for (std::size_t i = 0; i < keyed.size(); ++i) {
      order_[i] = keyed[i].second;
      if (i == 0 || keyed[i].first != keyed[i - 1].first) cells_[keyed[i].first].first = i;
      cells_[keyed[i].first].second = i + 1;
    }
  }

  /// The points within r of c (r at most the cell edge), appended to `out`.
  void near(const Eigen::Vector3d& c, double r, std::vector<Eigen::Vector3d>& out) const {
    out.clear();
    const std::int64_t cx = cell_of(c.x()), cy = cell_of(c.y()), cz = cell_of(c.z());
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(cx + dx, cy + dy, cz + dz));
          if (it == cells_.end()) continue;
          for (std::size_t k = it->second.first; k < it->second.second; ++k) {
            const Point3f& p = pts_[order_[k]];
            const Eigen::Vector3d q(p.x, p.y, p.z);
            if ((q - c).squaredNorm() <= r * r) out.push_back(q);
          }
        }
  }

 private:
  std::int64_t cell_of(double v) const { return static_cast<std::int64_t>(std::floor(v * inv_)); }
  static std::uint64_t key(std::int64_t x, std::int64_t y, std::int64_t z) {
    const auto part = [](std::int64_t v) { return static_cast<std::uint64_t>(v + (1 << 20)); };
    return (part(x) & 0x1FFFFF) | (part(y) & 0x1FFFFF) << 21 | (part(z) & 0x1FFFFF) << 42;
  }

  const std::vector<Point3f>& pts_;
  double inv_;
  std::vector<std::uint32_t> order_;
  std::unordered_map<std::uint64_t, std::pair<std::size_t, std::size_t>> cells_;
};

/// The noise of one patch, or a negative value when it is not a plane seen from the front.
inline double patch_noise(const std::vector<Eigen::Vector3d>& q, double r,
                          const PlaneNoiseParams& p) {
  if (q.size() < std::max<std::size_t>(p.min_points, 4)) return -1.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& v : q) mean += v;
  mean /= static_cast<double>(q.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& v : q) cov += (v - mean) * (v - mean).transpose();
  cov /= static_cast<double>(q.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d l = eig.eigenvalues().cwiseMax(0.0);  // ascending
  const double sd0 = std::sqrt(l[0]), sd1 = std::sqrt(l[1]);
  if (sd1 < r / 5 || sd0 > p.max_flatness * sd1 || mean.norm() <= 0) return -1.0;
  const double cos = std::abs(eig.eigenvectors().col(0).dot(mean.normalized()));
  if (cos < p.min_cos) return -1.0;
  const double n = static_cast<double>(q.size());
  return std::sqrt(l[0] * n / (n - 3)) / cos;
}

}  // namespace detail

/// One kept patch: its centre's range and its noise (m).
struct PatchNoise {
  double range = 0, noise = 0;
};

/// Appends the kept patches of `pts` (one scan, sensor frame) to `out`; several scans pool.
inline void add_patch_noise(const std::vector<Point3f>& pts, std::vector<PatchNoise>& out,
                            const PlaneNoiseParams& p = {}) {
  std::vector<Eigen::Vector3d> patch;
  const std::size_t stride = std::max<std::size_t>(p.stride, 1);
  const double* edges = detail::kPlaneNoiseEdges;
  for (std::size_t b = 0; b + 1 < std::size(detail::kPlaneNoiseEdges); ++b) {
    const detail::PatchGrid grid(pts, std::max(p.min_radius, p.radius_fraction * edges[b + 1]));
    for (std::size_t i = 0; i < pts.size(); i += stride) {
      const Eigen::Vector3d c(pts[i].x, pts[i].y, pts[i].z);
      const double range = c.norm();
      if (!(range >= edges[b] && range < edges[b + 1])) continue;
      const double r = std::max(p.min_radius, p.radius_fraction * range);
      grid.near(c, r, patch);
      const double noise = detail::patch_noise(patch, r, p);
      if (noise >= 0) out.push_back({range, noise});
    }
  }
}

/// The medians of kept patches, per range bin and over all.
inline PlaneNoise summarize_patch_noise(const std::vector<PatchNoise>& patches) {
  PlaneNoise out;
  std::vector<double> all, in_bin;
  const double* edges = detail::kPlaneNoiseEdges;
  for (std::size_t b = 0; b + 1 < std::size(detail::kPlaneNoiseEdges); ++b) {
    in_bin.clear();
    for (const PatchNoise& q : patches)
      if (q.range >= edges[b] && q.range < edges[b + 1]) in_bin.push_back(q.noise);
    out.bins.push_back({edges[b], edges[b + 1], in_bin.size(), detail::median_of(in_bin)});
    all.insert(all.end(), in_bin.begin(), in_bin.end());
  }
  out.patches = all.size();
  out.median = detail::median_of(std::move(all));
  return out;
}

/// The range-noise statistic of `pts` (one scan, sensor frame); see the top of this file.
inline PlaneNoise plane_fit_noise(const std::vector<Point3f>& pts, const PlaneNoiseParams& p = {}) {
  std::vector<PatchNoise> patches;
  add_patch_noise(pts, patches, p);
  return summarize_patch_noise(patches);
}

}  // namespace knnocc::sim
