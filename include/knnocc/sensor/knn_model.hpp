// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// KnnModel: the k-NN inverse sensor model (paper section 3.3, eq 13-15).
//
// An endpoint p with mean k-NN distance s (from the tracker) gets the probability
//   Prob(s) = P_u - Phi(s) / Phi(w*sigma + mu) * (P_u - P_w)                      (eq 13)
// with Phi the CDF of the tracker's normal distribution N(mu, sigma). Since
// Phi(w*sigma + mu) = Phi_std(w), the denominator is a constant and Prob(mu + w*sigma) = P_w.
// The endpoint casts a free ray only if logit(Prob) > logit(P_w) (eq 14), i.e. Prob > P_w, which
// for sigma > 0 is s < mu + w*sigma;
// its node receives logit(Prob) (summed over the scan's endpoints in the node, eq 15).
//
// Defined edge cases (documented in docs/library.md, tested):
//   - Prob is kept inside [kMinProb, P_u]: for large s eq 13 falls to or below 0 when
//     Phi_std(w) <= 1 - P_w / P_u (small or negative w); the floor keeps logit finite (-6.9);
//   - s NaN (the point has fewer than k neighbours or is not in the map cloud): the least reliable
//     rating, the limit of eq 13 for s -> +inf (no free ray);
//   - sigma == 0 (N == 1, or all valid s equal; sigma <= 1e-9 |mu| counts as 0, since Welford
//     leaves equal values a few ulps apart): Phi becomes the step at mu (the limit
//     sigma -> 0): s < mu gives P_u, s == mu gives P_u - (P_u - P_w) / (2 Phi_std(w)) (a ray when
//     w > 0: all-equal clouds, e.g. duplicates with s = 0, are consistent), s > mu the limit for
//     s -> +inf;
//   - N == 0 (no valid point yet): no distribution, every endpoint gets exactly P_w: weak occupied
//     evidence and no free ray.
//
// Thread safety: immutable after construction; share it freely.

#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "../core/config.hpp"
#include "../core/log_odds.hpp"
#include "../knn/tracker.hpp"
#include "../knn/tracker_types.hpp"
#include "../stats/welford.hpp"
#include "endpoint_rating.hpp"

namespace knnocc {

// Defaults: the best of the documented sweep (bench/bench_knn_sweep.cpp; docs/results.md, "The
// paper's experiment and the k-NN model's defaults").
struct KnnModelParams {
  std::size_t k = kDefaultK;  ///< neighbours per map point (s_p = mean distance to them)
  double w = 0.0;             ///< reliability threshold: s < mu + w * sigma casts a free ray
  double p_upper = 0.9;       ///< P_u: probability of the most reliable endpoints
  double p_w = 0.65;          ///< P_w: probability at s = mu + w * sigma
  double p_free = 0.4;        ///< free-ray probability (l_free = logit(p_free)); OctoMap's miss
  double s_limit = std::numeric_limits<double>::infinity();  ///< valid s_p < s_limit

  /// Rejects values the model is undefined for (std::invalid_argument; abort without exceptions).
  void validate() const {
    if (k < 1 || k > 4096)
      detail::invalid_argument("k must be in [1, 4096], got " + num(double(k)));
    if (!(w >= -8.0 && w <= 8.0)) detail::invalid_argument("w must be in [-8, 8], got " + num(w));
    if (!(p_w > 0.5 && p_w < 1.0))
      detail::invalid_argument("P_w must be in (0.5, 1), got " + num(p_w));
    if (!(p_upper > p_w && p_upper < 1.0))
      detail::invalid_argument("P_u must be in (P_w, 1) = (" + num(p_w) + ", 1), got " +
                               num(p_upper));
    if (!(p_free > 0.0 && p_free < 0.5))
      detail::invalid_argument("free probability must be in (0, 0.5), got " + num(p_free));
    if (!(s_limit > 0.0)) detail::invalid_argument("s_limit must be > 0, got " + num(s_limit));
  }

  TrackerParams tracker_params() const {
    TrackerParams t;
    t.k = k;
    t.s_limit = s_limit;
    return t;
  }

 private:
  static std::string num(double v) { return std::to_string(v); }
};

class KnnModel {
 public:
  /// The model needs the map point cloud's k-NN statistics (a rated model,
  /// sensor/sensor_model.hpp): Mapper keeps a tracker_type for it, made from tracker_params().
  static constexpr bool uses_map_cloud = true;
  using tracker_type = KnnTracker<>;
  /// Lowest probability an endpoint gets (keeps logit finite).
  static constexpr double kMinProb = 1e-3;
  /// sigma <= kFlatSigma * |mu| counts as sigma == 0 (rounding of equal values).
  static constexpr double kFlatSigma = 1e-9;

  explicit KnnModel(KnnModelParams params = {}) : params_(params) {
    params_.validate();
    phi_w_ = std_normal_cdf(params_.w);
    miss_ = static_cast<float>(logodds(params_.p_free));
  }

  const KnnModelParams& params() const { return params_; }
  TrackerParams tracker_params() const { return params_.tracker_params(); }
  float miss_logodds() const { return miss_; }

  /// Eq 13 for a mean k-NN distance s under the distribution; see the edge cases above.
  double probability(double s, const RunningNormal& dist) const {
    if (dist.count() == 0) return params_.p_w;
    const double mu = dist.mean(), sigma = dist.sigma();
    double cdf = 1.0;  // s NaN: the limit s -> +inf
    if (!std::isnan(s)) {
      // Equal values leave Welford's mean and sigma a few ulps off (six times 0.1 gives
      // sigma 5e-18): below kFlatSigma * |mu| the distribution counts as flat, and s within
      // that band of mu as equal to it.
      const double band = kFlatSigma * std::fabs(mu);
      if (sigma > band)
        cdf = std_normal_cdf((s - mu) / sigma);
      else
        cdf = s < mu - band ? 0.0 : s > mu + band ? 1.0 : 0.5;
    }
    const double p = params_.p_upper - cdf / phi_w_ * (params_.p_upper - params_.p_w);
    return p < kMinProb ? kMinProb : p;
  }

  /// Eq 14 (free ray iff logit(Prob) > logit(P_w), i.e. Prob > P_w) and the endpoint's term of
  /// eq 15.
  EndpointRating rate(double s, const RunningNormal& dist) const {
    const double p = probability(s, dist);
    return EndpointRating{static_cast<float>(logodds(p)), p > params_.p_w};
  }

  static double std_normal_cdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

 private:
  KnnModelParams params_;
  double phi_w_ = 0.5;
  float miss_ = 0.0f;
};

}  // namespace knnocc
