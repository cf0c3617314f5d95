// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// RobustModel: an inverse sensor model for sparse visual-SLAM keyframes whose points carry
// map-point ids (ORB-SLAM map points), for wrong matches that cluster and that the SLAM system
// re-observes; beyond the paper. docs/robust_model.md has the measurements, the constants and how
// each was chosen, the ablations and where the model loses.
//
// A contextual model (sensor/contextual_model.hpp): it keeps a ledger of the map points
// (sensor/map_point_ledger.hpp) and per-voxel counts (sensor/voxel_tally.hpp), and its rules are:
//   - a keyframe sees through a map point when one of its rays crosses the point's voxel and ends
//     more than margin_scale mean k-NN distances (mu) beyond it; every ray counts, whatever the
//     model decides about its endpoint, before and after the point appeared, but each map point a
//     ray ends at counts once against a voxel: re-detecting it is not a new look through the voxel
//     (sensor/voxel_tally.hpp, witnesses);
//   - a map point is believed real when P(real | its detections, see-throughs, independent support
//     and SLAM found/visible counts) >= 1/2, under a two-class mixture whose rates are estimated
//     from all map points of the sequence so far (sensor/real_point_mixture.hpp), one EM step per
//     keyframe;
//   - the mixture is used only while its wrong class is less supported by other keyframes' points
//     than its real class; otherwise it has found no wrong matches, and every point is believed;
//   - a believed point's detection adds the paper's eq 13 log-odds of its s (from two detections
//     on never below P_w while no keyframe has seen through its voxel) and, from its third
//     detection on, casts a free ray unless the ray would cross a voxel holding another believed
//     point: such a ray contradicts believed structure, and which of the two is wrong is the
//     mixture's to decide from the see-through it counts, not the ray's to settle by carving (a
//     wrong match re-detected behind a real surface otherwise carves the surface and the space
//     behind it); while the mixture has found no wrong class there is nothing to decide and every
//     such ray is cast; the first detection that finds it believed adds its earlier detections'
//     evidence too;
//   - one keyframe's endpoints in a voxel add their mean, not their sum (eq 15 bounded), also
//     when their evidence is added later;
//   - a point that stops being believed takes its evidence back from its voxel (a voxel left
//     without a believed point is not left occupied); one that becomes believed between its
//     detections adds its evidence then, without a ray;
//   - without map-point ids (dense sensors) every endpoint is rated as OctoMap's model rates it,
//     and Mapper keeps no map point cloud (map_cloud_without_ids).
// BasicRobustModel<Rules> lets bench/ measure variants of the rules RobustRules names; the
// library's model is RobustModel = BasicRobustModel<RobustRules>.
//
// Thread safety: written by its Mapper's insert (one writer); const queries are safe while no
// insert runs.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "../core/config.hpp"
#include "../core/detail/flat_index.hpp"
#include "../core/log_odds.hpp"
#include "../knn/change_set.hpp"
#include "../knn/tracker.hpp"
#include "../map/occupancy_map.hpp"
#include "../stats/welford.hpp"
#include "contextual_model.hpp"
#include "endpoint_rating.hpp"
#include "knn_model.hpp"
#include "map_point_ledger.hpp"
#include "real_point_mixture.hpp"
#include "voxel_tally.hpp"

namespace knnocc {

struct RobustModelParams {
  KnnModelParams knn = {};  ///< eq 13 for the strength of a believed point's evidence
  /// A ray sees through a point when it ends more than margin_scale * mu beyond it, mu the mean
  /// k-NN distance of the map point cloud (docs/robust_model.md: how 2 was chosen).
  double margin_scale = 2.0;
  double p_hit = 0.7;  ///< endpoints without map-point ids (OctoMap's hit)

  void validate() const {
    knn.validate();
    if (!(margin_scale >= 0 && margin_scale <= 100))
      detail::invalid_argument("margin_scale must be in [0, 100], got " +
                               std::to_string(margin_scale));
    if (!(p_hit > 0.5 && p_hit < 1.0))
      detail::invalid_argument("hit probability must be in (0.5, 1), got " + std::to_string(p_hit));
  }
};

/// The rules a variant may change (bench/robust_variants.hpp); RobustModel uses these.
struct RobustRules {
  /// Optional terms of the mixture.
  static constexpr MixtureTerms terms{};
  /// A believed point's detection casts its free ray from this many detections on (measured
  /// against 1 and 2 on the tuning seeds and the stereo set: fewer wrongly carved voxels and more
  /// nodes in shell, docs/robust_model.md).
  static constexpr std::uint32_t ray_detections = 3;
  /// The mixture is used only while its wrong class is less supported than its real class.
  static constexpr bool support_check = true;
  /// A map point a ray ends at counts once per voxel it sees through, not once per keyframe that
  /// re-detects it (no constant; measured against once per keyframe on the tuning seeds' grid,
  /// docs/robust_model.md).
  static constexpr bool witness_once = true;
  /// Free rays that would cross a voxel holding another believed point are cast too (false: not
  /// cast; measured as witness_once).
  static constexpr bool rays_through_believed = false;
  /// The strength floor P_w (from two detections on) holds only while no keyframe has seen
  /// through the point's voxel; then eq 13 of its s rates it as it is (no constant; true: the floor
  /// for every believed point, the rule before; docs/robust_model.md measures both).
  static constexpr bool floor_when_seen_through = false;
  /// What the mixture sees of a map point. The SLAM system's count of keyframes observing the
  /// point stands in for the detections when it is larger (keyframes not given to the mapper).
  static PointCounts counts(const MapPointLedger::Point& p, const VoxelTally& tally) {
    PointCounts k;
    k.d = std::max(p.views, p.slam.observations);
    k.c = p.voxel == VoxelTally::kNone ? 0 : tally.passes_at(p.voxel);
    k.u = p.support;
    if (p.slam.has_ratio()) k.f = p.slam.found, k.v = p.slam.visible;
    k.g = p.last - p.first + 1 - p.views;
    return k;
  }
};

template <class Rules = RobustRules>
class BasicRobustModel {
 public:
  static constexpr bool uses_map_cloud = true;
  /// Keyframes without map-point ids are rated as OctoMap's model rates them: Mapper keeps no
  /// map point cloud (and no k-NN statistics) for them.
  static constexpr bool map_cloud_without_ids = false;
  using tracker_type = KnnTracker<>;

  explicit BasicRobustModel(RobustModelParams params = {})
      : params_(params), knn_(params.knn), mixture_(Rules::terms) {
    params_.validate();
    hit_ = static_cast<float>(logodds(params_.p_hit));
    floor_ = logodds(params_.knn.p_w);
  }

  const RobustModelParams& params() const { return params_; }
  TrackerParams tracker_params() const { return params_.knn.tracker_params(); }
  float miss_logodds() const { return knn_.miss_logodds(); }

  /// The map points and what the model knows of each.
  const MapPointLedger& map_points() const { return ledger_; }
  /// Per-voxel see-throughs and believed points.
  const VoxelTally& voxels() const { return tally_; }
  /// The mixture (its rates: rates()).
  const RealPointMixture& mixture() const { return mixture_; }
  const RealPointRates& rates() const { return mixture_.rates(); }
  /// False while the mixture's wrong class is not less supported than its real class (then every
  /// map point is believed).
  bool wrong_class_found() const {
    return !Rules::support_check || mixture_.rates().u_wrong < mixture_.rates().u_real;
  }
  /// What the mixture sees of a map point.
  PointCounts counts(const MapPointLedger::Point& p) const { return Rules::counts(p, tally_); }
  /// Log-odds that a map point is real, with the current rates (+inf: no wrong class found).
  double real_log_odds(const MapPointLedger::Point& p) const {
    if (!wrong_class_found()) return std::numeric_limits<double>::infinity();
    return mixture_.log_odds(counts(p));
  }

  /// The contextual hook, before the scan (sensor/contextual_model.hpp).
  template <class Key, class Tracker>
  void rate_keyframe(const KeyframeView<Key, Tracker>& kf, std::vector<EndpointRating>& ratings) {
    count_per_voxel(kf);
    const RunningNormal& dist = kf.tracker.distribution();
    for (std::size_t j = 0; j < kf.points.size(); ++j) {
      const std::uint64_t id = kf.ids[j];
      if (id == KeyframeUnion::kNoId) continue;  // rated by Mapper: truncated ray only
      const float share = in_voxel_[j] > 1 ? 1.0f / static_cast<float>(in_voxel_[j]) : 1.0f;
      if (!kf.has_ids) {  // OctoMap's model (one hit per voxel and scan)
        ratings[j] = EndpointRating{hit_ * share, true};
        continue;
      }
      bool counted = false;
      const std::uint32_t i = observe(kf, j, counted);
      index_[j] = i;
      MapPointLedger::Point& p = ledger_.at(i);
      if (counted) p.shares += share;  // once per keyframe, as its views
      if (!kf.evidence.empty()) p.slam = kf.evidence[j];
      touch(i, kf.index);
      if (real_log_odds(p) < 0.0) {
        ratings[j] = EndpointRating{0.0f, false};
        continue;
      }
      const double l = strength(kf.tracker, id, dist, p) * (p.believed ? share : p.shares);
      ratings[j] = EndpointRating{static_cast<float>(l), p.views >= Rules::ray_detections};
    }
    if (kf.has_ids) see_through(kf, ratings);
  }

  /// The contextual hook, after the ratings: the evidence added, one EM step (with the
  /// keyframe's see-throughs), and every point's evidence put in or taken back accordingly, as
  /// edits applied after the keyframe's scan.
  template <class Key, class Tracker>
  void settle_keyframe(const KeyframeView<Key, Tracker>& kf,
                       const std::vector<EndpointRating>& ratings, std::vector<MapEdit>& edits) {
    if (!kf.has_ids) return;
    for (std::size_t j = 0; j < kf.points.size(); ++j) {
      if (kf.ids[j] == KeyframeUnion::kNoId || ratings[j].logodds == 0.0f) continue;
      MapPointLedger::Point& p = ledger_.at(index_[j]);
      p.added += ratings[j].logodds;
      set_believed(p, true);
    }
    // The points whose counts changed move to their new bins; then one EM step.
    for (const std::uint32_t i : touched_) {
      MapPointLedger::Point& p = ledger_.at(i);
      if (p.bin != MapPointLedger::kNone) mixture_.erase(p.bin);
      p.bin = mixture_.insert(counts(p));
    }
    touched_.clear();
    mixture_.step();
    mixture_.refresh();
    const RunningNormal& dist = kf.tracker.distribution();
    const bool found = wrong_class_found();
    ledger_.for_each([&](std::uint64_t id, MapPointLedger::Point& p) {
      const bool real = !found || mixture_.bin_log_odds(p.bin) >= 0.0;
      if (real == p.believed) return;
      if (!real) {
        take_back(p, edits);
        return;
      }
      const float l = static_cast<float>(strength(kf.tracker, id, dist, p) * p.shares);
      if (p.has_key) edits.push_back(MapEdit{p.key, l, false});
      p.added = l;
      set_believed(p, true);
    });
  }

 private:
  // The keyframe's see-throughs (sensor/voxel_tally.hpp; with witnesses unless a variant turns them
  // off), before its scan: a ray that crosses a voxel holding a believed point other than its own
  // endpoint's is not cast (see the rules above).
  template <class Key, class Tracker>
  void see_through(const KeyframeView<Key, Tracker>& kf, std::vector<EndpointRating>& ratings) {
    const RunningNormal& dist = kf.tracker.distribution();
    if (dist.count() == 0) return;  // the margin needs a scale
    crosses_.assign(kf.points.size(), 0);
    tally_.add_keyframe(
        kf.grid, kf.origin, kf.points, params_.margin_scale * dist.mean(),
        static_cast<std::uint32_t>(kf.index),
        [&](std::size_t j) { return kf.ids[j] != KeyframeUnion::kNoId; },
        [&](std::size_t j) { return Rules::witness_once ? index_[j] : MapPointLedger::kNone; },
        [&](std::uint32_t slot) {
          for (std::uint32_t i = tally_.at(slot).first_point; i != MapPointLedger::kNone;
               i = ledger_.at(i).next_in_voxel)
            touch(i, kf.index);
        },
        [&](std::size_t j, std::uint32_t slot) {
          if (tally_.at(slot).believed > 0 && index_[j] != MapPointLedger::kNone &&
              ledger_.at(index_[j]).voxel != slot)
            crosses_[j] = 1;
        });
    // Without a wrong class there is nothing for the mixture to decide: every ray is cast.
    if (Rules::rays_through_believed || !wrong_class_found()) return;
    for (std::size_t j = 0; j < kf.points.size(); ++j)
      if (crosses_[j]) ratings[j].casts_ray = false;
  }

  // Detection j of the keyframe in the ledger; a new point gets its voxel and its independent
  // support: the map points within margin_scale * mu (the see-through margin: one scale for
  // "near") that other keyframes created, each of which counts the new point too.
  template <class Key, class Tracker>
  std::uint32_t observe(const KeyframeView<Key, Tracker>& kf, std::size_t j, bool& counted) {
    bool fresh = false;
    const auto keyframe = static_cast<std::uint32_t>(kf.index);
    const std::uint32_t self = ledger_.observe(kf.ids[j], kf.points[j], keyframe, fresh, counted);
    if (!fresh) return self;
    MapPointLedger::Point& p = ledger_.at(self);
    Key k;  // as the scan finds the endpoint's voxel (float)
    p.has_key = kf.grid.point_to_key(detail::to_point3f(p.position), k);
    if (p.has_key) {
      p.key = k.pack();
      p.voxel = tally_.slot(k);
      p.next_in_voxel = tally_.at(p.voxel).first_point;
      tally_.at(p.voxel).first_point = self;
    }
    const RunningNormal& dist = kf.tracker.distribution();
    if (dist.count() == 0 || !kf.tracker.contains(kf.ids[j])) return self;
    const double r = params_.margin_scale * dist.mean();
    kf.tracker.radius(kf.tracker.position(kf.ids[j]), r * r, near_);
    for (const auto i : near_) {
      const std::uint32_t other = ledger_.index_of(kf.tracker.id_at(i));
      if (other == MapPointLedger::kNone || other == self) continue;
      MapPointLedger::Point& o = ledger_.at(other);
      if (o.first == keyframe) continue;  // the same creator
      ++o.support;
      ++ledger_.at(self).support;
      touch(other, kf.index);
    }
    return self;
  }

  // Point i's counts changed in keyframe `keyframe`: its bin is renewed at the keyframe's end.
  void touch(std::uint32_t i, std::size_t keyframe) {
    MapPointLedger::Point& p = ledger_.at(i);
    const auto stamp = static_cast<std::uint32_t>(keyframe + 1);
    if (p.touched == stamp) return;
    p.touched = stamp;
    touched_.push_back(i);
  }

  void set_believed(MapPointLedger::Point& p, bool believed) {
    if (p.believed == believed) return;
    p.believed = believed;
    if (p.voxel != VoxelTally::kNone) tally_.at(p.voxel).believed += believed ? 1 : -1;
  }

  // A point no longer believed takes its evidence back. A voxel left without a believed point is
  // not left occupied by what clamping kept of that evidence (or by an exact 0 where the point's
  // evidence alone made it known): the edit sets it just below the occupancy threshold.
  void take_back(MapPointLedger::Point& p, std::vector<MapEdit>& edits) {
    set_believed(p, false);
    const float added = p.added;
    p.added = 0.0f;
    if (!p.has_key || added == 0.0f) return;
    edits.push_back(MapEdit{p.key, -added, tally_.at(p.voxel).believed == 0});
  }

  // Eq 13 for the point's s; from two detections on never below P_w (a point two keyframes agree
  // on is not pushed to free) while no keyframe has seen through its voxel (a see-through
  // contradicts that agreement, and the paper's s decides); otherwise the paper's rating as it is.
  // A keyframe's see-throughs are counted after its ratings: the keyframe that first sees through
  // the voxel still rates its own detections there with the floor.
  template <class Tracker>
  double strength(const Tracker& tracker, std::uint64_t id, const RunningNormal& dist,
                  const MapPointLedger::Point& p) const {
    const double s =
        tracker.contains(id) ? tracker.s(id) : std::numeric_limits<double>::quiet_NaN();
    const double l = logodds(knn_.probability(s, dist));
    const bool floored =
        p.views >= 2 && (Rules::floor_when_seen_through || p.voxel == VoxelTally::kNone ||
                         tally_.passes_at(p.voxel) == 0);
    return floored ? std::max(l, floor_) : l;
  }

  // in_voxel_[j]: this keyframe's rated endpoints in endpoint j's voxel.
  template <class Key, class Tracker>
  void count_per_voxel(const KeyframeView<Key, Tracker>& kf) {
    const std::size_t n = kf.points.size();
    keys_.assign(n, detail::FlatIndex::kEmpty);
    in_voxel_.assign(n, 1);
    index_.assign(n, MapPointLedger::kNone);
    voxels_.clear();
    voxel_count_.clear();
    for (std::size_t j = 0; j < n; ++j) {
      Key k;
      if (kf.ids[j] == KeyframeUnion::kNoId ||
          !kf.grid.point_to_key(detail::to_point3f(kf.points[j]), k))
        continue;
      keys_[j] = k.pack();
      bool fresh = false;
      const std::uint32_t v =
          voxels_.find_or_insert(keys_[j], static_cast<std::uint32_t>(voxel_count_.size()), fresh);
      if (fresh) voxel_count_.push_back(0);
      ++voxel_count_[v];
    }
    for (std::size_t j = 0; j < n; ++j)
      if (keys_[j] != detail::FlatIndex::kEmpty)
        in_voxel_[j] = voxel_count_[voxels_.find(keys_[j])];
  }

  RobustModelParams params_;
  KnnModel knn_;
  float hit_ = 0.0f;
  double floor_ = 0.0;
  MapPointLedger ledger_;
  VoxelTally tally_;
  RealPointMixture mixture_;
  // Per keyframe (kept for their memory).
  std::vector<std::uint64_t> keys_;  // each endpoint's voxel (Key::pack(), kEmpty: none)
  std::vector<std::uint32_t> in_voxel_, voxel_count_, near_, touched_;
  std::vector<std::uint32_t> index_;   // each endpoint's ledger index (kNone: not rated by it)
  std::vector<std::uint8_t> crosses_;  // each ray crosses a voxel holding another believed point
  detail::FlatIndex voxels_;
};

/// The library's robust model.
using RobustModel = BasicRobustModel<>;

}  // namespace knnocc
