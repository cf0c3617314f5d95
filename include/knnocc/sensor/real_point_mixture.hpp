// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RealPointMixture: whether a map point is real structure or a wrong match, from counts the
// keyframes give, with what real structure and wrong matches look like estimated from the
// sequence itself: no rate comes from a simulator or from another data set.
//
// A map point's counts (PointCounts):
//   d  keyframes that detected it;
//   c  keyframes that saw through it (a ray crossed its voxel and ended well beyond,
//      sensor/voxel_tally.hpp);
//   u  map points near it that other keyframes created (independent support);
//   f, v  the SLAM system's found and visible counts, when it gave them (core/point_evidence.hpp);
//   g  keyframes between its first and latest detection that did not detect it (gaps; a term only
//      a variant turns on, MixtureTerms::gaps: docs/robust_model.md says why it is off).
// Two classes, real and wrong, with class-conditional distributions (naive Bayes):
//   c given n = d + c        binomial, see-through rate e_real / e_wrong
//   u                        geometric, mean u_real / u_wrong (a variant: negative binomial,
//                            below)
//   f given v, when v > 0    binomial, found rate f_real / f_wrong
//   g, when d >= 2 (gaps)    geometric, mean g_real / g_wrong
//   the class                prior = P(real)
// so that (G(x; m) = (1 - q) q^x with q = m / (1 + m))
//   log-odds(real) = logit(prior) + c log(e_r / e_w) + d log((1 - e_r) / (1 - e_w))
//                    + log(G(u; u_r) / G(u; u_w)) + f log(f_r / f_w)
//                    + (v - f) log((1 - f_r) / (1 - f_w)) [+ log(G(g; g_r) / G(g; g_w))].
// The variant MixtureTerms::nb_support makes support negative binomial (each class's mean and
// variance; Poisson where the variance is not above the mean): it fits surfaces' support, which
// gathers around its mean, and so condemns any point with little support, sparse real structure
// such as a textured ground as much as a lone wrong match (docs/robust_model.md: measured and not
// kept).
// The parameters are fitted to all map points by expectation-maximisation on the histogram of
// their counts (points with equal counts share their responsibilities), from the previous
// estimate; each estimate has one pseudo-observation on either side (a Beta(1, 1) prior for the
// rates and the prior, one pseudo-point of count 1 for the means and support's second moment),
// so that a short sequence stays defined. Support's variance (for the variant) is its
// responsibility-weighted moment (a moment step, not the negative binomial's maximum likelihood).
// The wrong class is the one seen through more often (the classes are swapped when an estimate says
// otherwise).
//
// Thread safety: one writer.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "../core/detail/flat_index.hpp"

namespace knnocc {

/// What the keyframes say about one map point (see above).
struct PointCounts {
  std::uint32_t d = 0;  ///< detections
  std::uint32_t c = 0;  ///< see-throughs
  std::uint32_t u = 0;  ///< independent support
  std::uint32_t f = 0;  ///< SLAM found count (with v; 0 and 0: not given)
  std::uint32_t v = 0;  ///< SLAM visible count
  std::uint32_t g = 0;  ///< gaps (used only with MixtureTerms::gaps)
};

/// Which optional terms the mixture uses.
struct MixtureTerms {
  bool gaps = false;  ///< the gap term (off: docs/robust_model.md, "measured and not kept")
  /// Support negative binomial (mean and variance per class) instead of geometric (off:
  /// docs/robust_model.md, "measured and not kept").
  bool nb_support = false;
};

/// The mixture's parameters.
struct RealPointRates {
  double prior = 0.5;         ///< fraction of the map points that are real
  double e_real = 0.05;       ///< P(see-through | a keyframe met it), real structure
  double e_wrong = 0.5;       ///< the same, wrong matches
  double u_real = 10.0;       ///< mean independent support, real structure
  double u_wrong = 1.0;       ///< the same, wrong matches
  double u_var_real = 110.0;  ///< variance of the independent support, real structure
  double u_var_wrong = 2.0;   ///< the same, wrong matches (both used only with nb_support)
  double f_real = 0.5;        ///< SLAM found / visible, real structure
  double f_wrong = 0.2;       ///< the same, wrong matches
  double g_real = 5.0;        ///< mean gaps (points detected twice or more), real structure
  double g_wrong = 0.5;       ///< the same, wrong matches
};

class RealPointMixture {
 public:
  explicit RealPointMixture(MixtureTerms terms = {}) : terms_(terms) { update(); }

  const RealPointRates& rates() const { return r_; }
  const MixtureTerms& terms() const { return terms_; }

  /// Log-odds that a point with these counts is real (see above).
  double log_odds(const PointCounts& k) const {
    double l = logit_prior_ + static_cast<double>(k.c) * per_pass_ +
               static_cast<double>(k.d) * per_detection_ + support_term(k.u);
    if (k.v > 0)
      l += static_cast<double>(k.f) * per_found_ + static_cast<double>(k.v - k.f) * per_unfound_;
    if (terms_.gaps && k.d >= 2) l += gap_base_ + static_cast<double>(k.g) * per_gap_;
    return l;
  }

  /// The histogram of the map points' counts: clear() and add() each, or keep it up to date with
  /// insert() and erase() as points' counts change; then step() or fit().
  void clear() {
    index_.clear();
    with_slam_.clear();
    bins_.clear();
    bin_log_odds_.clear();
    largest_support_ = 0;
  }
  void add(const PointCounts& k) { ++bins_[bin(k)].points; }
  /// A point with counts k joins the histogram; returns its bin (stable).
  std::uint32_t insert(const PointCounts& k) {
    const std::uint32_t b = bin(k);
    ++bins_[b].points;
    return b;
  }
  /// A point leaves bin b.
  void erase(std::uint32_t b) { --bins_[b].points; }
  /// Log-odds of bin b's counts, as of the last refresh().
  double bin_log_odds(std::uint32_t b) const { return bin_log_odds_[b]; }
  /// Computes every bin's log-odds with the current rates (for bin_log_odds()).
  void refresh() {
    bin_log_odds_.resize(bins_.size());
    for (std::size_t b = 0; b < bins_.size(); ++b)
      if (bins_[b].points > 0) bin_log_odds_[b] = log_odds(bins_[b].k);
  }

 private:
  // The bin of counts k, made when new.
  std::uint32_t bin(PointCounts k) {
    // Counts keep their value below 2^16 - 1 (larger ones share the top bin; f and v are scaled
    // together so that f <= v holds).
    auto cap = [](std::uint32_t x) { return std::min<std::uint32_t>(x, 0xFFFE); };
    k.d = cap(k.d), k.c = cap(k.c), k.u = cap(k.u), k.g = terms_.gaps ? cap(k.g) : 0;
    largest_support_ = std::max(largest_support_, std::min(k.u, kSupportTable - 1));
    if (k.v > 0xFFFE)
      k.f = static_cast<std::uint32_t>(std::uint64_t{k.f} * 0xFFFE / k.v), k.v = 0xFFFE;
    const std::uint64_t key = std::uint64_t{k.d} | std::uint64_t{k.c} << 16 |
                              std::uint64_t{k.u} << 32 | std::uint64_t{k.g} << 48;
    std::uint32_t i = 0;
    bool fresh = false;
    if (k.v == 0) {
      i = index_.find_or_insert(key, static_cast<std::uint32_t>(bins_.size()), fresh);
    } else {  // with the SLAM system's counts: a second table
      const auto it = with_slam_.try_emplace(SlamKey{key, std::uint64_t{k.f} << 32 | k.v},
                                             static_cast<std::uint32_t>(bins_.size()));
      i = it.first->second;
      fresh = it.second;
    }
    if (fresh) bins_.push_back(Bin{k, 0});
    return i;
  }

 public:
  /// Number of distinct counts collected.
  std::size_t bins() const { return bins_.size(); }

  /// One expectation-maximisation step from the current estimate.
  void step() {
    Sums s;
    for (const Bin& b : bins_) {
      if (b.points == 0) continue;
      // From log-odds 37 on P(real) is 1 in double (e^-37 is below half an ulp of 1): most bins
      // of a sequence are there, and take neither exp nor the wrong class's sums.
      const double l = log_odds(b.k);
      if (l >= 37.0)
        s.add_real(b);
      else
        s.add(b, 1.0 / (1.0 + std::exp(-l)));
    }
    if (s.all == 0) return;
    const double wrong = s.all - s.w;
    r_.prior = (s.w + 1) / (s.all + 2);
    r_.e_real = (s.w_c + 1) / (s.w_n + 2);
    r_.e_wrong = (s.v_c + 1) / (s.v_n + 2);
    r_.u_real = (s.w_u + 1) / (s.w + 1);
    r_.u_wrong = (s.v_u + 1) / (wrong + 1);
    r_.u_var_real = (s.w_uu + 1) / (s.w + 1) - r_.u_real * r_.u_real;
    r_.u_var_wrong = (s.v_uu + 1) / (wrong + 1) - r_.u_wrong * r_.u_wrong;
    r_.f_real = (s.w_f + 1) / (s.w_v + 2);
    r_.f_wrong = (s.v_f + 1) / (s.v_v + 2);
    r_.g_real = (s.w_g + 1) / (s.w_m + 1);
    r_.g_wrong = (s.v_g + 1) / (s.v_m + 1);
    if (r_.e_real > r_.e_wrong) {  // the wrong class is the one seen through more often
      std::swap(r_.e_real, r_.e_wrong);
      std::swap(r_.u_real, r_.u_wrong);
      std::swap(r_.u_var_real, r_.u_var_wrong);
      std::swap(r_.f_real, r_.f_wrong);
      std::swap(r_.g_real, r_.g_wrong);
      r_.prior = 1 - r_.prior;
    }
    update();
  }

  /// Log-likelihood of the collected counts under the current estimate (up to terms equal for
  /// both classes).
  double log_likelihood() const {
    double ll = 0;
    for (const Bin& b : bins_) {
      const double a = class_log(b.k, true), z = class_log(b.k, false), m = std::max(a, z);
      ll += b.points * (m + std::log(std::exp(a - m) + std::exp(z - m)));
    }
    return ll;
  }

  /// Steps until no parameter moves by more than `tolerance` (relative), at most `max_steps`;
  /// returns the steps taken.
  int fit(double tolerance = 1e-6, int max_steps = 1000) {
    for (int i = 1; i <= max_steps; ++i) {
      const RealPointRates before = r_;
      step();
      if (close(before, r_, tolerance)) return i;
    }
    return max_steps;
  }

 private:
  struct Bin {
    PointCounts k;
    std::uint32_t points;
  };
  struct SlamKey {
    std::uint64_t counts, slam;
    bool operator==(const SlamKey& o) const { return counts == o.counts && slam == o.slam; }
  };
  struct SlamKeyHash {
    std::size_t operator()(const SlamKey& k) const {
      return std::hash<std::uint64_t>{}(k.counts * 0x9e3779b97f4a7c15ULL ^ k.slam);
    }
  };
  // The weighted counts of one E-step (w: P(real), the real class; v_: the wrong class).
  struct Sums {
    double w_uu = 0, v_uu = 0;
    double all = 0, w = 0, w_n = 0, w_c = 0, v_n = 0, v_c = 0, w_u = 0, v_u = 0, w_f = 0, w_v = 0,
           v_f = 0, v_v = 0, w_m = 0, v_m = 0, w_g = 0, v_g = 0;
    void add(const Bin& b, double p) {
      const double m = b.points, q = 1 - p, n = static_cast<double>(b.k.d) + b.k.c;
      all += m;
      w += m * p;
      w_n += m * p * n;
      w_c += m * p * b.k.c;
      v_n += m * q * n;
      v_c += m * q * b.k.c;
      w_u += m * p * b.k.u;
      v_u += m * q * b.k.u;
      w_uu += m * p * double(b.k.u) * b.k.u;
      v_uu += m * q * double(b.k.u) * b.k.u;
      w_f += m * p * b.k.f;
      w_v += m * p * b.k.v;
      v_f += m * q * b.k.f;
      v_v += m * q * b.k.v;
      if (b.k.d >= 2) {
        w_m += m * p;
        v_m += m * q;
        w_g += m * p * b.k.g;
        v_g += m * q * b.k.g;
      }
    }
    // add(b, 1) to the last bit: each product with p = 1 is the product without it, and the
    // wrong class's terms (products with q = 0) add +0.
    void add_real(const Bin& b) {
      const double m = b.points, n = static_cast<double>(b.k.d) + b.k.c;
      all += m;
      w += m;
      w_n += m * n;
      w_c += m * b.k.c;
      w_u += m * b.k.u;
      w_uu += m * double(b.k.u) * b.k.u;
      w_f += m * b.k.f;
      w_v += m * b.k.v;
      if (b.k.d >= 2) {
        w_m += m;
        w_g += m * b.k.g;
      }
    }
  };

  // The support term of the log-odds (see above): geometric, or with nb_support the two classes'
  // log NB(u) less log u! (equal for both), from the table update() fills.
  double support_term(std::uint32_t u) const {
    if (!terms_.nb_support) return support_base_ + static_cast<double>(u) * per_support_;
    if (u < support_table_.size()) return support_table_[u];
    return support_log(u, true) - support_log(u, false);
  }
  // The table of support_term for u = 0 .. the largest support collected (at most 4095), one log
  // a step for each class's log Gamma(u + r) / Gamma(r): the same sums support_log(u, real) adds.
  void fill_support_table() {
    support_table_.clear();
    if (!terms_.nb_support) return;
    double rising[2] = {0.0, 0.0};
    for (std::uint32_t x = 0; x <= largest_support_; ++x) {
      if (x > 0)
        for (int c = 0; c < 2; ++c) rising[c] += std::log(dispersion(c == 0) + (x - 1));
      support_table_.push_back(support_log(x, true, rising[0]) - support_log(x, false, rising[1]));
    }
  }
  static constexpr std::uint32_t kSupportTable = 4096;
  // The negative binomial's r = mean^2 / (variance - mean) of a class; 0 for Poisson (variance
  // not above the mean by 0.01 %).
  double dispersion(bool real) const {
    const double m = real ? r_.u_real : r_.u_wrong, v = real ? r_.u_var_real : r_.u_var_wrong;
    return v > m * 1.0001 ? m * m / (v - m) : 0.0;
  }
  // log NB(u; mean, variance) of a class less log u!: log Gamma(u + r) / Gamma(r) (`rising`, a
  // sum of u logs) + r log(r / (r + mean)) + u log(mean / (r + mean)); Poisson's
  // u log(mean) - mean.
  double support_log(std::uint32_t u, bool real, double rising) const {
    const double m = real ? r_.u_real : r_.u_wrong, r = dispersion(real);
    const double x = static_cast<double>(u);
    if (r == 0.0) return x * std::log(m) - m;
    return rising + r * std::log(r / (r + m)) + x * std::log(m / (r + m));
  }
  double support_log(std::uint32_t u, bool real) const {
    const double r = dispersion(real);
    double rising = 0;
    for (std::uint32_t i = 0; r > 0.0 && i < u; ++i) rising += std::log(r + i);
    return support_log(u, real, rising);
  }

  // log(P(class) P(counts | class)), the class real or wrong.
  double class_log(const PointCounts& k, bool real) const {
    auto geo = [](double x, double mean) {
      const double q = mean / (1 + mean);
      return std::log(1 - q) + x * std::log(q);
    };
    const double e = real ? r_.e_real : r_.e_wrong, f = real ? r_.f_real : r_.f_wrong;
    const double support =
        terms_.nb_support ? support_log(k.u, real) : geo(k.u, real ? r_.u_real : r_.u_wrong);
    double l = std::log(real ? r_.prior : 1 - r_.prior) + k.c * std::log(e) +
               k.d * std::log(1 - e) + support;
    if (k.v > 0) l += k.f * std::log(f) + (k.v - k.f) * std::log(1 - f);
    if (terms_.gaps && k.d >= 2) l += geo(k.g, real ? r_.g_real : r_.g_wrong);
    return l;
  }

  static bool close(const RealPointRates& a, const RealPointRates& b, double tol) {
    auto near = [tol](double x, double y) { return std::fabs(x - y) <= tol * std::max(x, y); };
    return near(a.prior, b.prior) && near(a.e_real, b.e_real) && near(a.e_wrong, b.e_wrong) &&
           near(a.u_real, b.u_real) && near(a.u_wrong, b.u_wrong) && near(a.f_real, b.f_real) &&
           near(a.f_wrong, b.f_wrong) && near(a.g_real, b.g_real) && near(a.g_wrong, b.g_wrong);
  }

  void update() {
    logit_prior_ = std::log(r_.prior / (1 - r_.prior));
    per_pass_ = std::log(r_.e_real / r_.e_wrong);
    per_detection_ = std::log((1 - r_.e_real) / (1 - r_.e_wrong));
    auto q = [](double mean) { return mean / (1 + mean); };
    support_base_ = std::log((1 - q(r_.u_real)) / (1 - q(r_.u_wrong)));
    per_support_ = std::log(q(r_.u_real) / q(r_.u_wrong));
    fill_support_table();
    per_found_ = std::log(r_.f_real / r_.f_wrong);
    per_unfound_ = std::log((1 - r_.f_real) / (1 - r_.f_wrong));
    gap_base_ = std::log((1 - q(r_.g_real)) / (1 - q(r_.g_wrong)));
    per_gap_ = std::log(q(r_.g_real) / q(r_.g_wrong));
  }

  MixtureTerms terms_;
  RealPointRates r_;
  double logit_prior_ = 0, per_pass_ = 0, per_detection_ = 0, support_base_ = 0, per_support_ = 0,
         per_found_ = 0, per_unfound_ = 0, gap_base_ = 0, per_gap_ = 0;
  detail::FlatIndex index_;  // packed (d, c, u, g) -> bin, points without SLAM counts
  std::unordered_map<SlamKey, std::uint32_t, SlamKeyHash> with_slam_;
  std::vector<Bin> bins_;
  std::vector<double> bin_log_odds_;
  std::vector<double> support_table_;  // support_term(u) at index u, for these rates
  std::uint32_t largest_support_ = 0;  // the largest u collected, below kSupportTable
};

}  // namespace knnocc
