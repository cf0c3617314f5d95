// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Knn2022Model: the authors' follow-up model (Miao, Hunter, Georgilas, "An Occupancy Mapping
// Method Based on K-Nearest Neighbours", Sensors 22(1):139, 2022), a cloud-rated sensor model
// (sensor/cloud_model.hpp). Their code was not found; this follows a description of
// the authors' public code (docs/evaluation.md), which also lists the choices made where that
// description is silent.
//
// Per keyframe (points in the world frame, sensor at o):
//   inner points  the finite points within inner_range (4 m) of o;
//   d             of an inner point: the mean distance to its k nearest neighbours among the
//                 keyframe's inner points (fewer when the keyframe has fewer; +inf for a point
//                 alone, which gets p_far);
//   p(d)          = p_near - (p_near - p_far) F(d), F the CDF of N(mu, sigma) truncated at 0:
//                 F(d) = (Phi((d - mu) / sigma) - Phi(-mu / sigma)) / (1 - Phi(-mu / sigma)),
//                 so p(0) = p_near and p falls to p_far as d grows (sigma 0: F the step at mu);
//   occupied      an inner point's voxel receives logit(p(d)), summed over the keyframe's inner
//                 points in it and applied once (a voxel holding only far-spread points, p_far <
//                 0.5, loses probability) and is not freed by the same keyframe;
//   free          rays to inner points update their voxels with p_miss (OctoMap's 0.4); rays of
//                 the other points, cut at inner_range, with the weaker p_miss_outer; a voxel on
//                 both gets p_miss, once (LayeredScanInserter).
// mu and sigma: online, the running statistics (RunningNormal, Welford, stats/welford.hpp) of
// every inner point's d so far, this keyframe's added before it is rated; or fixed, from a first
// pass over the sequence as the authors did (Knn2022Params::fixed_statistics, mu, sigma; the
// first pass adds each keyframe's distances() to a RunningNormal).
//
// Defaults: inner_range (4 m) and p_miss (OctoMap's 0.4) as summarised above. The authors' k,
// p_near, p_far and outer miss were not found; they are chosen by bench/bench_knn_sweep --model
// knn2022 on the simulator's tuning seeds (docs/results.md): the F1 of the authors' counting rises
// slowly towards p_near -> 1 and large k (the rating fading out), so the defaults are the smallest
// k, then p_near, within 0.003 of the sweep's best F1 with p_far <= 0.45 (logit -0.2: a voxel
// holding only far-spread points still loses probability).
//
// Thread safety: rate_cloud() learns (online statistics); const queries are safe while no
// rate_cloud() runs.

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "../core/config.hpp"
#include "../core/log_odds.hpp"
#include "../core/point3.hpp"
#include "../knn/point_index.hpp"
#include "../stats/welford.hpp"
#include "layered_rating.hpp"

namespace knnocc {

struct Knn2022Params {
  std::size_t k = 24;             ///< neighbours of an inner point within its keyframe
  double inner_range = 4.0;       ///< inner points lie within this range of the sensor (m)
  double p_near = 0.97;           ///< p_U: probability of a point at d = 0
  double p_far = 0.45;            ///< p_W: the limit of p(d) as d grows (< 0.5: evidence against)
  double p_miss = 0.4;            ///< free update of rays to inner points (OctoMap's miss)
  double p_miss_outer = 0.45;     ///< free update of the other rays, cut at inner_range
  bool fixed_statistics = false;  ///< mu, sigma below (a first pass) instead of running ones
  double mu = 0.0, sigma = 0.0;   ///< fixed_statistics only

  /// Rejects values the model is undefined for (std::invalid_argument; abort without exceptions).
  void validate() const {
    if (k < 1 || k > 4096)
      detail::invalid_argument("k must be in [1, 4096], got " + std::to_string(k));
    if (!(inner_range > 0.0 && inner_range < 1e6))
      detail::invalid_argument("inner range must be in (0, 1e6) m, got " + num(inner_range));
    if (!(p_far > 0.0 && p_far < 1.0))
      detail::invalid_argument("p_far must be in (0, 1), got " + num(p_far));
    if (!(p_near > p_far && p_near < 1.0))
      detail::invalid_argument("p_near must be in (p_far, 1) = (" + num(p_far) + ", 1), got " +
                               num(p_near));
    if (!(p_miss > 0.0 && p_miss < 0.5))
      detail::invalid_argument("miss probability must be in (0, 0.5), got " + num(p_miss));
    if (!(p_miss_outer >= p_miss && p_miss_outer < 0.5))
      detail::invalid_argument("outer miss probability must be in [p_miss, 0.5) = [" + num(p_miss) +
                               ", 0.5), got " + num(p_miss_outer));
    if (fixed_statistics && !(mu >= 0.0 && sigma >= 0.0 && std::isfinite(mu + sigma)))
      detail::invalid_argument("fixed statistics need finite mu >= 0 and sigma >= 0");
  }

 private:
  static std::string num(double v) { return std::to_string(v); }
};

class Knn2022Model {
 public:
  /// A cloud-rated model (sensor/cloud_model.hpp): Mapper uses LayeredScanInserter for it.
  static constexpr bool rates_cloud = true;
  /// sigma <= kFlatSigma * mu counts as sigma == 0 (rounding of equal values).
  static constexpr double kFlatSigma = 1e-9;

  explicit Knn2022Model(Knn2022Params params = {}) : params_(params) {
    params_.validate();
    layers_.strong_miss = logodds(params_.p_miss);
    layers_.weak_miss = logodds(params_.p_miss_outer);
    layers_.weak_range = params_.inner_range;
  }

  const Knn2022Params& params() const { return params_; }
  float miss_logodds() const { return layers_.strong_miss; }
  RayLayers ray_layers() const { return layers_; }
  /// The running statistics of the inner points' d so far (online); empty with fixed ones.
  const RunningNormal& distribution() const { return running_; }
  double mu() const { return params_.fixed_statistics ? params_.mu : running_.mean(); }
  double sigma() const { return params_.fixed_statistics ? params_.sigma : running_.sigma(); }

  /// d of every point (NaN for the points that are not inner points, +inf for an inner point
  /// without a neighbour).
  void distances(const Point3d& origin, const std::vector<Point3d>& points,
                 std::vector<double>& d) const {
    const double r2 = params_.inner_range * params_.inner_range;
    d.assign(points.size(), std::numeric_limits<double>::quiet_NaN());
    PointIndex index;
    for (std::size_t j = 0; j < points.size(); ++j)
      if (std::isfinite(points[j].x + points[j].y + points[j].z) && dist2(points[j], origin) <= r2)
        index.append(j, points[j]);
    index.flush();
    std::vector<Neighbor> nn;
    for (PointIndex::index_type i = 0; i < index.size(); ++i) {
      index.knn(i, params_.k, nn);
      double sum = 0.0;
      for (const Neighbor& n : nn) sum += std::sqrt(n.d2);
      d[index.id(i)] = nn.empty() ? std::numeric_limits<double>::infinity()
                                  : sum / static_cast<double>(nn.size());
    }
  }

  /// p(d) under the current statistics (see the header comment).
  double probability(double d) const {
    const double mu = this->mu(), sigma = this->sigma();
    const bool none = !params_.fixed_statistics && running_.count() == 0;
    double f = 1.0;  // d = +inf, or no statistics yet: p_far
    if (!none && std::isfinite(d)) {
      if (sigma > kFlatSigma * mu) {
        const double below = std_normal_cdf(-mu / sigma);
        f = (std_normal_cdf((d - mu) / sigma) - below) / (1.0 - below);
        f = f < 0.0 ? 0.0 : f > 1.0 ? 1.0 : f;
      } else {
        const double band = kFlatSigma * mu;
        f = d < mu - band ? 0.0 : d > mu + band ? 1.0 : 0.5;
      }
    }
    if (f >= 1.0) return params_.p_far;  // exactly, not p_near - (p_near - p_far)
    return params_.p_near - (params_.p_near - params_.p_far) * f;
  }

  /// The cloud-rated concept: inner points are hits with logit(p(d)) and strong rays, the others
  /// weak rays cut at inner_range (online: the keyframe's d join the statistics first).
  void rate_cloud(const Point3d& origin, const std::vector<Point3d>& points,
                  std::vector<LayeredRating>& ratings) {
    distances(origin, points, d_);
    if (!params_.fixed_statistics)
      for (const double d : d_)
        if (std::isfinite(d)) running_.add(d);
    ratings.resize(points.size());
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (std::isnan(d_[j])) {
        ratings[j] = LayeredRating{0.0f, false, RayLayer::weak};
        continue;
      }
      ratings[j] = LayeredRating{logodds(probability(d_[j])), true, RayLayer::strong};
    }
  }

  static double std_normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

 private:
  Knn2022Params params_;
  RayLayers layers_;
  RunningNormal running_;
  std::vector<double> d_;  // scratch of rate_cloud
};

/// The authors' first pass over a sequence: add() every keyframe (world points, sensor origin),
/// then params() are the parameters with fixed_statistics, mu and sigma of every inner point's d.
class Knn2022FirstPass {
 public:
  explicit Knn2022FirstPass(Knn2022Params params = {}) : model_(params) {}

  void add(const Point3d& origin, const std::vector<Point3d>& points) {
    model_.distances(origin, points, d_);
    for (const double d : d_)
      if (std::isfinite(d)) all_.add(d);
  }
  const RunningNormal& distribution() const { return all_; }
  Knn2022Params params() const {
    Knn2022Params p = model_.params();
    p.fixed_statistics = true;
    p.mu = all_.mean();
    p.sigma = all_.sigma();
    return p;
  }

 private:
  Knn2022Model model_;
  RunningNormal all_;
  std::vector<double> d_;
};

}  // namespace knnocc
