#pragma once
// RobustModel: an inverse sensor model for sparse visual-SLAM keyframes with realistic wrong
// matches (clustered, repeated, worse with depth), beyond the paper's k-NN model (knn_model.hpp,
// which it keeps for the s part). It rates each endpoint from its PointContext
// (sensor/point_context.hpp), which Mapper gathers for it:
//
//   - multi-view support: an endpoint whose map point has been observed by fewer than min_views
//     keyframes adds nothing and casts no ray yet (a wrong match is mostly seen by one keyframe);
//   - re-rating at confirmation: the first keyframe whose endpoint of a map point adds evidence
//     (normally the one that brings it to min_views) adds what the earlier, deferred observations
//     would have added (views times its own);
//   - independent support at a second scale: a confirmed map point commits evidence only once at
//     least min_support (1) other map points within support_scale (1.75) * mu (mu: the mean of
//     the k-NN distances s) were created by keyframes other than its own creator; until then it is
//     deferred like an unconfirmed one, and the count is taken again at each observation as the
//     cloud grows. A wrong patch is a few points of one keyframe's stereo matching sharing one
//     depth error, with nothing else near: s at the paper's k cannot tell it from sparse real
//     structure, which other keyframes' points soon surround;
//   - early commitment: a map point seen by early_views (2) keyframes commits already when
//     early_support (12) independent points surround it (sparse views of dense real structure;
//     a wrong patch has none);
//   - temporal consistency for patches: a confirmed map point with span_siblings (4) or more
//     points of its own creator within the support radius (a patch of one keyframe's matching)
//     commits only once a keyframe at least min_span (5) keyframes after its creator observes
//     it (span_support: an exemption for patches that many independent points surround, off by
//     default: with the near rule below it gives back no real structure, and lets wrong patches
//     among other wrong points through). A wrong patch that the SLAM
//     system fails to cull is re-observed by the next few keyframes, then vanishes; real
//     structure keeps being observed while in view. Applied to every point (not only patches)
//     it costs the real stereo set many multi-view voxels: there 18 % of them hold only points
//     seen within five consecutive keyframes (bench/diag_robust_model.cpp);
//   - lone points: a map point that is not a patch, observed over lone_span (5) keyframes
//     since its creator, commits without independent support (sparse real structure). Patches
//     are left out: a wrong patch re-observed past lone_span keyframes would commit
//     (bench_robust_model --repeat 8), and the real stereo set gives the same map either way;
//   - measured and not kept (diag_robust_model prints the geometry): the angle spread of a
//     point's viewing rays, and support counted only from creators more than a few keyframes
//     away. The real set's keyframes are close together: its multi-view points are seen under
//     small angles (median spread 14 degrees, against 23-34 for the simulator's wrong patches)
//     and supported by neighbouring keyframes' points, so both lose real structure there;
//   - structure beside committed structure: a map point that the rules above hold back adds
//     occupied evidence, but casts no ray, once its voxel or one of the 26 around it holds an
//     anchor, a map point that committed by the rules above (when the point is observed with an
//     anchor already there, or, without a new observation, at the end of the keyframe that made
//     the anchor; points committed by this rule anchor nothing, so it never chains). Sparse
//     real structure continues committed structure; a wrong match mostly lies off it. On the
//     real stereo set the voxels that the rules above kept alone were mostly isolated because
//     their neighbours' points were seen by one or two keyframes; this rule fills those in
//     (fewer isolated and fewer lost multi-view voxels) and adds no irrelevant nodes in the
//     simulator (bench_robust_model --ablate, "-near");
//   - s: a confirmed endpoint's probability is eq 13's, but never below P_w (a point several
//     keyframes agree on is not pushed towards free, however sparse its neighbourhood);
//   - free rays from ray_views (4) views on: a map point three keyframes agree on adds occupied
//     evidence, but carves space only once a fourth one does (fewer wrongly carved voxels in the
//     simulator, fewer lost and free multi-view voxels on the real stereo set);
//   - one keyframe's endpoints in one voxel add their mean, not their sum (eq 15 bounded: a patch
//     of wrong matches cannot outvote the rays through it);
//   - free-space evidence, both off by default (measured in the bench, they no longer pay): an
//     endpoint whose voxel already holds log-odds below free_veto adds no occupied evidence
//     unless its map point has veto_views views; contra_min other keyframes' rays passing
//     through a map point take its evidence back (insertion/map_point_ledger.hpp);
//   - without map-point ids (dense sensors: depth cameras, LiDAR) there is no multi-view support:
//     every endpoint is rated as OctoMap's model rates it (hit, ray), so dense input keeps its
//     structure (the paper's s-rating removes far, sparser surfaces there); Mapper then keeps no
//     map point cloud, so its tracker() stays empty (map_cloud_without_ids).
// Each part can be switched off in RobustModelParams to measure it (bench/bench_robust_model.cpp).
//
// Thread safety: its ledger is written by its Mapper's insert (one writer).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "../core/config.hpp"
#include "../core/key.hpp"
#include "../core/log_odds.hpp"
#include "../knn/change_set.hpp"
#include "../knn/tracker.hpp"
#include "../map/occupancy_map.hpp"
#include "../stats/welford.hpp"
#include "contextual_model.hpp"
#include "endpoint_rating.hpp"
#include "knn_model.hpp"
#include "map_point_ledger.hpp"
#include "point_context.hpp"

namespace knnocc {

struct RobustModelParams {
  KnnModelParams knn = {};      ///< eq 13 for the s part (k, w, P_u, P_w, free probability)
  std::uint32_t min_views = 3;  ///< keyframes that confirm a map point (1: no deferral)
  std::uint32_t ray_views = 4;  ///< a committed endpoint casts its ray from this many views on
  bool rerate = true;           ///< the confirming keyframe adds the deferred evidence
  bool use_s = true;            ///< eq 13 (floored at P_w); false: OctoMap's hit for all
  bool bound_voxel = true;      ///< one keyframe adds the mean of its endpoints in a voxel
  double free_veto = -std::numeric_limits<double>::infinity();           ///< see above (off)
  std::uint32_t veto_views = std::numeric_limits<std::uint32_t>::max();  ///< immune from veto
  double p_hit = 0.7;  ///< endpoints without map-point ids (OctoMap's hit), and use_s = false
  /// Free-space evidence (insertion/map_point_ledger.hpp): a map point is rejected, and its
  /// evidence taken back, once at least contra_min other keyframes' rays passed within
  /// contra_radius of it and ended more than contra_margin beyond it, and at least contra_ratio
  /// times its views did (contra_min 0: off, the default: with independent support it no longer
  /// pays, and its ray walk costs a fifth of the model's time; bench/bench_robust_model.cpp).
  std::uint32_t contra_min = 0;
  double contra_ratio = 0.5;
  double contra_radius = 0.05;  ///< m
  double contra_margin = 0.3;   ///< m
  /// Lowest probability of a confirmed endpoint (s part): P_w by default; 0.5 adds nothing
  double p_floor = -1;  ///< < 0: P_w
  /// Independent support at a second scale (see above; support_scale 0 or min_support 0: off).
  double support_scale = 1.75;
  std::uint32_t min_support = 1;
  /// A map point with early_views (< min_views) views commits once early_support independent
  /// points surround it (early_views 0: off): real structure seen twice in a dense region.
  std::uint32_t early_views = 2;
  std::uint32_t early_support = 12;
  /// Temporal consistency for patches (see above; min_span 0: off): a map point with at least
  /// span_siblings other points of its own creator within the support radius commits only once
  /// a keyframe at least min_span keyframes after its creator observes it, unless span_support
  /// independent points surround it (the largest value, the default: no such exemption;
  /// span_siblings 0: the rule applies to every point).
  std::uint32_t min_span = 5;
  std::uint32_t span_support = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t span_siblings = 4;
  /// A map point observed over at least lone_span keyframes since its creator commits without
  /// independent support (0: off).
  std::uint32_t lone_span = 5;
  /// The lone rule for patches too (off: a wrong patch that the SLAM system keeps re-observing
  /// past lone_span keyframes would otherwise commit without support; bench_robust_model
  /// --repeat 8).
  bool lone_patches = false;
  /// Structure beside committed structure (0: off): a map point seen by at least near_views
  /// keyframes that the rules above hold back adds its occupied evidence, without a ray, once
  /// its voxel or one of the 26 around it holds an anchor, a map point that committed by those
  /// rules (PointContext::anchors).
  std::uint32_t near_views = 1;

  void validate() const {
    knn.validate();
    if (min_views < 1 || min_views > 1000)
      detail::invalid_argument("min_views must be in [1, 1000], got " + std::to_string(min_views));
    if (!(p_hit > 0.5 && p_hit < 1.0))
      detail::invalid_argument("hit probability must be in (0.5, 1), got " + std::to_string(p_hit));
    if (!(p_floor < 0 || (p_floor >= 0.5 && p_floor < 1)))
      detail::invalid_argument("p_floor must be in [0.5, 1) (or < 0: P_w)");
    if (!(contra_ratio >= 0 && contra_ratio <= 100) ||
        !(contra_radius >= 0 && contra_radius < 10) || !(contra_margin >= 0 && contra_margin < 100))
      detail::invalid_argument(
          "contradiction: ratio in [0, 100], radius in [0, 10) m, margin in "
          "[0, 100) m");
    if (!(support_scale >= 0 && support_scale <= 100) || min_support > 100000)
      detail::invalid_argument("support: scale in [0, 100], min_support in [0, 100000]");
    if (std::isnan(free_veto) || free_veto > 0)
      detail::invalid_argument("free_veto must be <= 0 (or -inf: off)");
  }
};

class RobustModel {
 public:
  static constexpr bool uses_map_cloud = true;
  /// Keyframes without map-point ids are rated as OctoMap's model rates them: Mapper keeps no
  /// map point cloud (and no k-NN statistics) for them.
  static constexpr bool map_cloud_without_ids = false;
  using tracker_type = KnnTracker<>;

  explicit RobustModel(RobustModelParams params = {}) : params_(params), knn_(params.knn) {
    params_.validate();
    hit_ = static_cast<float>(logodds(params_.p_hit));
    floor_ = logodds(params_.p_floor < 0 ? params_.knn.p_w : params_.p_floor);
    ray_views_ = std::max(params_.ray_views, params_.min_views);
  }

  const RobustModelParams& params() const { return params_; }
  TrackerParams tracker_params() const { return params_.knn.tracker_params(); }
  float miss_logodds() const { return knn_.miss_logodds(); }

  /// One endpoint's occupied log-odds and free ray from its context (see the header comment).
  EndpointRating rate(const PointContext& c, const RunningNormal& dist) const {
    if (c.views == 0)  // no map-point ids: OctoMap's model (one hit per voxel and scan)
      return EndpointRating{c.in_voxel > 1 ? hit_ / static_cast<float>(c.in_voxel) : hit_, true};
    if (commits(c)) return EndpointRating{evidence(c, dist), c.views >= ray_views_};
    if (beside_anchor(c)) return EndpointRating{evidence(c, dist), false};
    return EndpointRating{0.0f, false};
  }

  /// The endpoint commits by the rules of its own map point (multi-view, independent support,
  /// early commitment, temporal consistency, lone points): its map point is then an anchor.
  bool commits(const PointContext& c) const {
    const bool early = params_.early_views > 0 && c.views >= params_.early_views &&
                       c.support != std::numeric_limits<std::uint32_t>::max() &&
                       c.support >= params_.early_support;
    const bool patch =
        params_.span_siblings == 0 || (c.siblings != std::numeric_limits<std::uint32_t>::max() &&
                                       c.siblings >= params_.span_siblings);
    const bool lone =
        params_.lone_span > 0 && c.span >= params_.lone_span && (params_.lone_patches || !patch);
    if ((c.views < params_.min_views && !early) || rejects(c.views, c.contradictions) ||
        (c.support < params_.min_support && !lone))
      return false;
    const bool surrounded =
        c.support != std::numeric_limits<std::uint32_t>::max() && c.support >= params_.span_support;
    return c.anchor || c.span >= params_.min_span || surrounded || !patch;
  }

  /// Mapper counts the anchors around the endpoint (PointContext::anchors) only when this says
  /// they can decide: the near rule is on, the point has near_views views and does not commit
  /// on its own.
  bool wants_anchors(const PointContext& c) const {
    return params_.near_views > 0 && c.views >= params_.near_views &&
           !rejects(c.views, c.contradictions) && !commits(c);
  }

  /// What a point that the rules hold back adds beside an anchor that appeared after its last
  /// observation (Mapper commits it then, without a ray); 0 when the near rule does not apply.
  float beside_evidence(const PointContext& c, const RunningNormal& dist) const {
    return beside_anchor(c) ? evidence(c, dist) : 0.0f;
  }

 private:
  bool beside_anchor(const PointContext& c) const {
    return params_.near_views > 0 && c.views >= params_.near_views && c.anchors > 0 &&
           c.anchors != std::numeric_limits<std::uint32_t>::max() &&
           !rejects(c.views, c.contradictions);
  }

  // The occupied log-odds of an endpoint that adds evidence: eq 13 floored at P_w, the deferred
  // views added at the first commitment, free_veto, the voxel's mean (eq 15 bounded).
  float evidence(const PointContext& c, const RunningNormal& dist) const {
    double l = hit_;
    if (params_.use_s) {
      const double p = knn_.probability(c.s, dist);
      l = std::max(static_cast<double>(logodds(p)), floor_);
    }
    if (params_.rerate && !c.committed) l *= c.views;
    if (c.voxel_logodds < params_.free_veto && c.views < params_.veto_views) l = 0.0;
    if (params_.bound_voxel && c.in_voxel > 1) l /= c.in_voxel;
    return static_cast<float>(l);
  }

 public:
  /// Free-space evidence outweighs the point's views (see RobustModelParams::contra_min).
  bool rejects(std::uint32_t views, std::uint32_t contradictions) const {
    return params_.contra_min > 0 && contradictions >= params_.contra_min &&
           contradictions >= params_.contra_ratio * views;
  }
  /// 0 when the contradiction test is off (Mapper then walks no rays for it).
  double contradiction_radius() const { return params_.contra_min > 0 ? params_.contra_radius : 0; }
  /// Radius (m) to count an endpoint's independent support in (PointContext::support); 0: not
  /// needed (support off, or the endpoint is not confirmed).
  double support_radius(std::uint32_t views, const RunningNormal& dist) const {
    const std::uint32_t from = params_.early_views > 0
                                   ? std::min(params_.early_views, params_.min_views)
                                   : params_.min_views;
    if (params_.support_scale <= 0 || params_.min_support == 0 || views < from || dist.count() == 0)
      return 0.0;
    return params_.support_scale * dist.mean();
  }
  double contradiction_margin() const { return params_.contra_margin; }

  /// What the model remembers per map-point id (views, evidence added, anchors, contradictions).
  const MapPointLedger& map_points() const { return ledger_; }

  /// The contextual hook (sensor/contextual_model.hpp): each endpoint's PointContext (its map
  /// point's views, first viewing direction and contradictions, its voxel's endpoints in this
  /// keyframe and log-odds so far), then rate() above.
  template <class Key, class Tracker>
  void rate_keyframe(const KeyframeView<Key, Tracker>& kf, std::vector<EndpointRating>& ratings) {
    const std::size_t n = kf.points.size();
    keys_.resize(n);
    key_ok_.assign(n, 0);
    beside_.assign(n, 0);
    per_voxel_.clear();
    for (std::size_t j = 0; j < n; ++j) {
      Key k;
      if (kf.ids[j] != KeyframeUnion::kNoId &&
          kf.map.grid().point_to_key(detail::to_point3f(kf.points[j]), k)) {
        keys_[j] = k.pack();
        key_ok_[j] = 1;
        ++per_voxel_[keys_[j]];
      }
    }
    const RunningNormal& dist = kf.tracker.distribution();
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint64_t id = kf.ids[j];
      if (id == KeyframeUnion::kNoId) continue;  // rated by Mapper: truncated ray only
      PointContext c;
      c.s = kf.tracker.contains(id) ? kf.tracker.s(id) : std::numeric_limits<double>::quiet_NaN();
      const Point3d& p = kf.points[j];
      const double dx = p.x - kf.origin.x, dy = p.y - kf.origin.y, dz = p.z - kf.origin.z;
      c.range = std::sqrt(dx * dx + dy * dy + dz * dz);
      c.keyframe = kf.index;
      if (key_ok_[j]) {
        c.in_voxel = per_voxel_[keys_[j]];
        if (const auto v = kf.map.logodds(Key::unpack(keys_[j]))) c.voxel_logodds = *v;
      }
      if (kf.has_ids) {
        const auto& e = ledger_.observe(id, p, kf.origin, kf.index, kf.map.grid());
        c.views = e.views;
        c.contradictions = e.contra;
        c.committed = e.added != 0.0f;
        c.anchor = e.anchor;
        c.parallax = MapPointLedger::parallax(e, p, kf.origin);
        c.span = kf.index - e.first;
        // Counted until the point commits on its own: the support decision is taken once.
        const double r = c.anchor ? 0.0 : support_radius(c.views, dist);
        if (r > 0) c.support = count_support(kf.tracker, id, e.first, r, c.siblings);
        if (key_ok_[j] && wants_anchors(c)) {
          c.anchors = ledger_.anchors_around(Key::unpack(keys_[j]));
          beside_[j] = 1;
        }
      }
      ratings[j] = rate(c, dist);
    }
  }

  /// After the scan: the evidence each map point added, the points held back beside this
  /// keyframe's new anchors, then the free-space evidence of this keyframe's rays against other
  /// map points (MapPointLedger::contradict).
  template <class Key, class Tracker>
  void settle_keyframe(const KeyframeView<Key, Tracker>& kf,
                       const std::vector<EndpointRating>& ratings, OccupancyMap<Key>& map) {
    if (!kf.has_ids) return;
    new_anchors_.clear();
    for (std::size_t j = 0; j < kf.points.size(); ++j) {
      if (kf.ids[j] == KeyframeUnion::kNoId || ratings[j].logodds == 0.0f) continue;
      if (auto* e = ledger_.find(kf.ids[j])) {
        e->added += ratings[j].logodds;
        if (!e->anchor && !beside_[j]) {  // committed beside anchors: not one itself
          e->anchor = true;
          if (e->has_key) new_anchors_.push_back(e->key);
        }
      }
    }
    commit_beside<Key>(kf, map);
    if (contradiction_radius() > 0)
      ledger_.contradict(
          kf.origin, kf.points, ratings, kf.index, contradiction_radius(), contradiction_margin(),
          map, [&](std::uint32_t views, std::uint32_t contra) { return rejects(views, contra); });
  }

 private:
  // Map points within r of map point `id` (the tracker's cloud) that a keyframe other than
  // `first` created (PointContext::support); `siblings`: the other map points within r that
  // `first` created (PointContext::siblings).
  template <class Tracker>
  std::uint32_t count_support(const Tracker& tracker, std::uint64_t id, std::size_t first, double r,
                              std::uint32_t& siblings) {
    siblings = 0;
    if (!tracker.contains(id)) return 0;
    tracker.radius(tracker.position(id), r * r, near_);
    std::uint32_t n = 0;
    for (const auto i : near_) {
      const std::uint64_t other = tracker.id_at(i);
      if (other == id) continue;
      const auto* e = ledger_.find(other);
      const bool independent = e == nullptr || e->first != first;
      n += independent;
      siblings += !independent;
    }
    return n;
  }

  // Map points held back before an anchor appeared beside them now add, to the voxel of their
  // first position, what they add beside anchors (near_views): the evidence does not depend on
  // whether the anchor or the point came first.
  template <class Key, class Tracker>
  void commit_beside(const KeyframeView<Key, Tracker>& kf, OccupancyMap<Key>& map) {
    const RunningNormal& dist = kf.tracker.distribution();
    for (const std::uint64_t a : new_anchors_)
      ledger_.for_each_around(Key::unpack(a), [&](std::uint64_t id, auto& p) {
        if (p.added != 0.0f || p.anchor || p.rejected || !p.has_key) return;
        PointContext c;
        c.s = kf.tracker.contains(id) ? kf.tracker.s(id) : std::numeric_limits<double>::quiet_NaN();
        c.views = p.views;
        c.span = kf.index - p.first;
        c.keyframe = kf.index;
        c.contradictions = p.contra;
        const Key k = Key::unpack(p.key);
        if (const auto v = map.logodds(k)) c.voxel_logodds = *v;
        c.anchors = 1;
        const float l = beside_evidence(c, dist);
        if (l == 0.0f) return;
        map.update(k, l);
        p.added = l;
      });
  }

  RobustModelParams params_;
  KnnModel knn_;
  float hit_ = 0.0f;
  double floor_ = 0.0;
  std::uint32_t ray_views_ = 1;
  MapPointLedger ledger_;
  // Per keyframe (kept for their memory).
  std::vector<std::uint64_t> keys_;  // each endpoint's voxel (Key::pack())
  std::vector<unsigned char> key_ok_;
  std::vector<unsigned char> beside_;  // rated from the anchors around it (wants_anchors)
  std::vector<std::uint64_t> new_anchors_;
  std::vector<std::uint32_t> near_;
  std::unordered_map<std::uint64_t, std::uint32_t> per_voxel_;
};

}  // namespace knnocc
