// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Mapper: one keyframe at a time into an occupancy map (paper Alg. 3, with Alg. 2 before it when
// the sensor model needs the map point cloud). Its parts are policies, each a concept documented
// where it is declared and checked with a static_assert that names what is missing:
//
//   Model       the inverse sensor model (sensor/sensor_model.hpp): OctoMapModel (eq 4, fixed
//               hit and miss log-odds), KnnModel (eq 13-15, every endpoint rated by its k-NN
//               statistics), a contextual model such as RobustModel (a whole keyframe rated
//               through the hook of sensor/contextual_model.hpp, by a model that keeps its own
//               per-map-point state) or a cloud-rated one such as Knn2022Model (each keyframe
//               rated from its own cloud, sensor/cloud_model.hpp)
//   Key         the map's key type (OcKey: OctoMap's 16-bit keys; WideKey for larger areas)
//   Tracker     the map point cloud's k-NN statistics (knn/tracker_concept.hpp), kept only for a
//               rated model; by default the model's tracker_type (KnnTracker for KnnModel)
//   Integrator  applies one scan's updates to the map (insertion/scan_integrator.hpp):
//               ScanInserter (exact DDA, occupied wins, one update per voxel per scan), or
//               LayeredScanInserter for a cloud-rated model
//
// Mapper<OctoMapModel>, Mapper<KnnModel>, Mapper<Knn2022Model> and Mapper<RobustModel> differ in
// one type and take the same keyframes. The model, the tracker and the map may be passed
// constructed (e.g. KnnTracker<PaperAnnulus> with its own dr and s_max, or a map read from a file
// to continue it); examples/custom_policies.cpp writes its own sensor model and tracker.
//
// One keyframe (insert_keyframe): its points in the world frame, the sensor position, and the
// map-point ids of the points when the source has them (ORB-SLAM map points). The map point cloud
// is the union of the keyframes' points (KeyframeUnion: an id joins once, at its first position;
// without ids every point of every keyframe is a new map point), or the caller gives its change
// explicitly (e.g. after bundle adjustment or map-point culling).
//   fixed model (OctoMapModel): OctoMap's insertPointCloud(points, origin, max_range, discretize).
//   rated model (KnnModel):     the change goes through the tracker (Alg. 2), every endpoint is
//                               rated with its s_{p,t} (eq 13, 14) and the scan applied with
//                               per-voxel sums (eq 15, Alg. 3).
//   cloud-rated model (Knn2022Model, sensor/cloud_model.hpp): no map cloud; the model rates the
//                               keyframe from its own points (rate_cloud) and the keyframe is
//                               applied with two layers of free space (insert_layered).
//   contextual model (RobustModel, sensor/contextual_model.hpp): as a rated model, with the
//                               model's rate_keyframe instead of eq 13-14 per endpoint;
//                               endpoints it rates {0, no ray} stay out of the scan; then its
//                               settle_keyframe.
// max_range keeps OctoMap's meaning for every model: a point farther than max_range from the
// sensor marks nothing occupied, casts its ray truncated at max_range, and (k-NN model) stays out
// of the map point cloud. Points with a NaN/Inf coordinate or outside the key range are skipped
// and counted (ScanStats) and stay out of the map cloud too.
//
// A Mapper is movable (its map lives on the heap, where the integrator points); a moved-from
// Mapper may only be destroyed or assigned to.
//
// Thread safety: one writer; const queries (map(), tracker(), model()) are safe from many threads
// while no insert runs.

#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/config.hpp"
#include "core/key.hpp"
#include "core/point3.hpp"
#include "core/point_evidence.hpp"
#include "core/point_traits.hpp"
#include "insertion/layered_scan_inserter.hpp"
#include "insertion/scan_inserter.hpp"
#include "insertion/scan_integrator.hpp"
#include "knn/change_set.hpp"
#include "knn/tracker_concept.hpp"
#include "knn/tracker_types.hpp"
#include "map/occupancy_map.hpp"
#include "raycast/dda.hpp"
#include "sensor/contextual_model.hpp"
#include "sensor/endpoint_rating.hpp"
#include "sensor/layered_rating.hpp"
#include "sensor/octomap_model.hpp"
#include "sensor/rated_keyframe.hpp"
#include "sensor/sensor_model.hpp"

namespace knnocc {

struct MapperOptions {
  double max_range = -1.0;  ///< < 0: no limit; 0 or NaN rejected
  bool discretize = false;  ///< OctoMapModel only: endpoints reduced to their distinct voxels
  unsigned threads = 1;     ///< threads that walk the rays of a scan (the map is the same)
  OccupancyParams occupancy = {};
};

/// What one insert_keyframe() did.
struct KeyframeStats {
  ScanStats scan;           ///< the map update
  TrackerUpdate tracker;    ///< the map point cloud's change (k-NN model; zero otherwise)
  std::size_t rated = 0;    ///< endpoints the k-NN model rated (with or without an s)
  std::size_t rays = 0;     ///< of those, the reliable ones that cast a free ray (eq 14)
  std::size_t unrated = 0;  ///< of those, the ones without an s (< k neighbours, or an id not
                            ///< in the map cloud): rated as for s -> infinity
};

namespace detail {
struct NoTracker {};
// The tracker a model names (Model::tracker_type), else none.
template <class M, class = void>
struct default_tracker {
  using type = NoTracker;
};
template <class M>
struct default_tracker<M, std::void_t<typename M::tracker_type>> {
  using type = typename M::tracker_type;
};
template <class M>
using default_tracker_t = typename default_tracker<M>::type;

template <class M, class = void>
struct has_tracker_params : std::false_type {};
template <class M>
struct has_tracker_params<M, std::void_t<decltype(std::declval<const M&>().tracker_params())>>
    : std::true_type {};

/// What the scan integrator does with an end point q seen from o (both as the float points it
/// casts): ScanStats counts the first three; only `inserted` points mark a voxel occupied.
enum class EndpointFate { nonfinite, beyond_max_range, out_of_range, inserted };
template <class Key>
EndpointFate endpoint_fate(const Grid<Key>& grid, const Point3f& q, const Point3f& o,
                           double max_range) {
  if (!finite(q)) return EndpointFate::nonfinite;
  if (max_range >= 0.0 && octomap_norm(q.x - o.x, q.y - o.y, q.z - o.z) > max_range)
    return EndpointFate::beyond_max_range;
  Key k;
  return grid.point_to_key(q, k) ? EndpointFate::inserted : EndpointFate::out_of_range;
}
}  // namespace detail

template <class Model = OctoMapModel, class Key = OcKey,
          class Tracker = detail::default_tracker_t<Model>,
          class Integrator = detail::default_integrator_t<Key, Model>>
class Mapper {
 public:
  using model_type = Model;
  using key_type = Key;
  using map_type = OccupancyMap<Key>;
  using tracker_type = Tracker;
  using integrator_type = Integrator;
  static constexpr bool uses_map_cloud = detail::uses_map_cloud<Model>::value;
  /// The model rates each keyframe from its own cloud (sensor/cloud_model.hpp).
  static constexpr bool rates_cloud = detail::rates_cloud<Model>::value;
  /// The model rates whole keyframes through the contextual hook (sensor/contextual_model.hpp).
  static constexpr bool contextual = uses_map_cloud && detail::is_contextual_v<Model, Key, Tracker>;

 private:
  // The concepts of the parts, each failing with a message that names what is missing.
  static constexpr bool check_parts() {
    detail::check_sensor_model<Model, Key, Tracker>();
    if constexpr (uses_map_cloud) {
      static_assert(!std::is_same_v<Tracker, detail::NoTracker>,
                    "a sensor model with uses_map_cloud = true needs a tracker: declare `using "
                    "tracker_type = ...` in the model or name Mapper's Tracker parameter");
      if constexpr (!std::is_same_v<Tracker, detail::NoTracker>) detail::check_tracker<Tracker>();
    }
    detail::check_scan_integrator<Integrator, Key, Model, uses_map_cloud>();
    return true;
  }
  static_assert(check_parts());

 public:
  /// A new map of `resolution` (with options.occupancy's clamping) and, for a rated model, a new
  /// tracker: Tracker(model.tracker_params()) when the model has them, else Tracker(). Rejects
  /// resolution <= 0 and bad options (std::invalid_argument; abort without exceptions).
  explicit Mapper(double resolution, Model model = Model(), MapperOptions options = {})
      : Mapper(map_type(resolution, options.occupancy), model, make_tracker(model), options) {}
  /// The same with the caller's tracker (e.g. KnnTracker<PaperAnnulus>(params, {dr, s_max})).
  Mapper(double resolution, Model model, Tracker tracker, MapperOptions options = {})
      : Mapper(map_type(resolution, options.occupancy), std::move(model), std::move(tracker),
               options) {}
  /// Continues `map` (e.g. read from an OctoMap .ot file; its own clamping applies and
  /// options.occupancy is not used). A rated model's tracker starts empty: the keyframes that made
  /// the map are not in its map point cloud.
  Mapper(map_type map, Model model, MapperOptions options = {})
      : Mapper(std::move(map), model, make_tracker(model), options) {}
  /// The same with the caller's tracker.
  Mapper(map_type map, Model model, Tracker tracker, MapperOptions options = {})
      : options_(checked(options)),
        map_(std::make_unique<map_type>(std::move(map))),
        model_(std::move(model)),
        tracker_(std::move(tracker)),
        integrator_(*map_, model_, options.threads) {}

  const map_type& map() const { return *map_; }
  map_type& map() { return *map_; }
  /// The model (a contextual model's state too, e.g. RobustModel::map_points()).
  const Model& model() const { return model_; }
  const MapperOptions& options() const { return options_; }
  /// The k-NN statistics of the map point cloud (only with a model that uses them; empty for
  /// keyframes without ids when the model rates them without it, as RobustModel does).
  template <bool B = uses_map_cloud, std::enable_if_t<B, int> = 0>
  const Tracker& tracker() const {
    return tracker_;
  }

  /// Alg. 3 for one keyframe: `points` in the world frame (any point type), seen from `origin`;
  /// `ids` one distinct map-point id per point, or empty (then each point is a new map point); a
  /// repeated id is std::invalid_argument. A sequence must either always or never give ids, and a
  /// Mapper takes keyframes through this overload or through the ChangeSet one, not both
  /// (std::invalid_argument). The OctoMap model ignores ids. A NaN/Inf origin inserts nothing and
  /// leaves the map cloud as it was (ScanStats::origin_valid == false).
  template <class Points, class Origin>
  KeyframeStats insert_keyframe(const Origin& origin, const Points& points,
                                const std::vector<std::uint64_t>& ids = {}) {
    return insert_keyframe(origin, points, ids, std::vector<PointEvidence>{});
  }

  /// The same with the SLAM system's evidence per point (core/point_evidence.hpp; one per point,
  /// or empty), which a contextual model may use; the other models ignore it.
  template <class Points, class Origin>
  KeyframeStats insert_keyframe(const Origin& origin, const Points& points,
                                const std::vector<std::uint64_t>& ids,
                                const std::vector<PointEvidence>& evidence) {
    if constexpr (!uses_map_cloud && !rates_cloud) {  // the caller's points, without a copy
      (void)ids;
      (void)evidence;
      KeyframeStats ks;
      ks.scan =
          integrator_.insert_point_cloud(origin, points, options_.max_range, options_.discretize);
      return ks;
    } else {
      KeyframeStats ks = rate(origin, points, ids, evidence, rated_);
      integrate_rated(ks);
      return ks;
    }
  }

  /// Alg. 3 with the map cloud's change given by the caller (k-NN model): `change` is applied to
  /// the tracker first, then the points (ids: one per point, the map points they observe) are
  /// rated with their s_{p,t}. A point whose id is not in the map cloud gets no s (unrated).
  template <class Points, class Origin, bool B = uses_map_cloud, std::enable_if_t<B, int> = 0>
  KeyframeStats insert_keyframe(const Origin& origin, const Points& points,
                                const std::vector<std::uint64_t>& ids, const ChangeSet& change) {
    use_mode(Mode::explicit_change);
    if (ids.size() != static_cast<std::size_t>(std::distance(std::begin(points), std::end(points))))
      detail::invalid_argument("insert_keyframe: one id per point expected");
    KeyframeStats ks;
    rated_.clear();
    rated_.kind = kind;
    if (!load(origin, points, ids, ks)) return ks;
    ids_given_ = true;
    ks.tracker = tracker_.apply(change);
    point_ids_.assign(world_.size(), KeyframeUnion::kNoId);
    for (std::size_t j = 0; j < world_.size(); ++j)
      if (within_range(j)) point_ids_[j] = ids[j];
    rate_loaded(ks, {}, rated_);
    integrate_rated(ks);
    return ks;
  }

  /// The first half of insert_keyframe (same arguments): the keyframe rated into `out` (its
  /// world-frame points as the integrator casts them, their ratings, a contextual model's edits;
  /// sensor/rated_keyframe.hpp) with the map point cloud, the tracker and the model's state
  /// updated, and the map untouched. integrate(out), here or in a map or tile elsewhere
  /// (tiles/tile_integrator.hpp), is the second half. Returns the rating's statistics (the scan's
  /// are integrate()'s; a non-finite origin: scan.origin_valid false and nothing to integrate).
  template <class Points, class Origin>
  KeyframeStats rate(const Origin& origin, const Points& points,
                     const std::vector<std::uint64_t>& ids,
                     const std::vector<PointEvidence>& evidence, RatedKeyframe& out) {
    KeyframeStats ks;
    out.clear();
    out.kind = kind;
    if constexpr (rates_cloud) {
      (void)ids;
      (void)evidence;
      if (!load(origin, points, {}, ks)) return ks;
      model_.rate_cloud(origin_, world_, out.layered);
      for (const LayeredRating& r : out.layered) {
        ks.rated += r.hit;
        ks.rays += r.ray == RayLayer::strong;
      }
      take_points(out);
    } else if constexpr (!uses_map_cloud) {
      (void)ids;
      (void)evidence;
      if (!load(origin, points, {}, ks)) return ks;
      take_points(out);
    } else {
      use_mode(Mode::keyframe_union);
      if (!load(origin, points, ids, ks)) return ks;
      if (!evidence.empty() && evidence.size() != world_.size())
        detail::invalid_argument("insert_keyframe: one PointEvidence per point expected");
      if constexpr (!detail::map_cloud_without_ids<Model>::value) {
        if (ids.empty() && !world_.empty()) {  // rated without the map cloud: none kept
          if (ids_given_)
            detail::invalid_argument("KeyframeUnion: keyframes with and without ids are mixed");
          without_ids_ = true;
          point_ids_.assign(world_.size(), KeyframeUnion::kNoId);
          for (std::size_t j = 0; j < world_.size(); ++j)
            if (within_range(j)) point_ids_[j] = j;  // any id: the model does not look it up
          rate_loaded(ks, evidence, out);
          return ks;
        }
        if (!ids.empty() && without_ids_)
          detail::invalid_argument("KeyframeUnion: keyframes with and without ids are mixed");
      }
      ids_given_ = !ids.empty();
      // Points beyond max_range stay out of the map cloud (they still cast their truncated ray).
      cloud_.clear();
      cloud_ids_.clear();
      for (std::size_t j = 0; j < world_.size(); ++j)
        if (within_range(j)) {
          cloud_.push_back(world_[j]);
          if (!ids.empty()) cloud_ids_.push_back(ids[j]);
        }
      const ChangeSet change = union_.add(cloud_, cloud_ids_, &cloud_map_ids_);
      point_ids_.assign(world_.size(), KeyframeUnion::kNoId);
      for (std::size_t j = 0, c = 0; j < world_.size(); ++j)
        if (within_range(j)) point_ids_[j] = cloud_map_ids_[c++];
      ks.tracker = tracker_.apply(change);
      rate_loaded(ks, evidence, out);
    }
    return ks;
  }

  /// The second half of insert_keyframe: a keyframe this Mapper's model rated (rate(), here or
  /// in another Mapper of the same model and options) into the map: its scan, then its edits.
  ScanStats integrate(const RatedKeyframe& rk) {
    if (rk.kind != kind) detail::invalid_argument("integrate: a keyframe of another kind of model");
    ScanStats st;
    if constexpr (rates_cloud) {
      st = integrator_.insert_layered(rk.origin, rk.points, rk.layered, model_.ray_layers(),
                                      options_.max_range);
    } else if constexpr (!uses_map_cloud) {
      st = integrator_.insert_point_cloud(rk.origin, rk.points, options_.max_range,
                                          options_.discretize);
    } else {
      st = integrator_.insert_rated(rk.origin, rk.points, rk.ratings, options_.max_range);
    }
    for (const MapEdit& e : rk.edits) apply_edit(*map_, e);
    return st;
  }

  /// What integrating this Mapper's rated keyframes needs besides them (a tile of the map:
  /// tiles/tile_integrator.hpp).
  IntegrationParams integration() const {
    IntegrationParams p;
    p.kind = kind;
    p.max_range = options_.max_range;
    p.discretize = options_.discretize;
    p.occupancy = map_->params();
    if constexpr (rates_cloud) {
      p.layers = model_.ray_layers();
      p.miss = p.layers.strong_miss;
    } else if constexpr (!uses_map_cloud) {
      p.hit = model_.hit_logodds();
      p.miss = model_.miss_logodds();
    } else {
      p.miss = model_.miss_logodds();
    }
    return p;
  }

  /// The kind of keyframe this Mapper's model rates (sensor/rated_keyframe.hpp).
  static constexpr RatingKind kind = rates_cloud      ? RatingKind::layered
                                     : uses_map_cloud ? RatingKind::rated
                                                      : RatingKind::fixed;

 private:
  static const MapperOptions& checked(const MapperOptions& o) {
    detail::check_max_range(o.max_range);
    if (o.threads < 1) detail::invalid_argument("threads must be >= 1");
    if ((uses_map_cloud || rates_cloud) && o.discretize)
      detail::invalid_argument("discretize applies to the OctoMap model only");
    return o;
  }

  static Tracker make_tracker(const Model& model) {
    if constexpr (detail::has_tracker_params<Model>::value) {
      if constexpr (std::is_constructible_v<Tracker, decltype(model.tracker_params())>)
        return Tracker(model.tracker_params());
      else
        return Tracker();
    } else {
      (void)model;
      return Tracker();
    }
  }

  // How the map cloud's changes arrive; mixing the two would let KeyframeUnion and the tracker
  // disagree about which ids exist.
  enum class Mode { unset, keyframe_union, explicit_change };
  void use_mode(Mode m) {
    if (mode_ == Mode::unset) mode_ = m;
    if (mode_ != m)
      detail::invalid_argument(
          "insert_keyframe: a Mapper takes keyframes either with their ChangeSet or without, "
          "not both");
  }

  // Loads the keyframe and checks its ids; false (with the stats of an empty insert) when the
  // origin is not finite: then nothing changes, not even the map cloud.
  template <class Origin, class Points>
  bool load(const Origin& origin, const Points& points, const std::vector<std::uint64_t>& ids,
            KeyframeStats& ks) {
    origin_ = to_point3d(origin);
    world_.clear();
    for (const auto& p : points) world_.push_back(to_point3d(p));
    if (!ids.empty() && ids.size() != world_.size())
      detail::invalid_argument("insert_keyframe: one id per point expected");
    for (const std::uint64_t id : ids)
      if (id == KeyframeUnion::kNoId)
        detail::invalid_argument("insert_keyframe: id 2^64-1 is reserved (KeyframeUnion::kNoId)");
    detail::check_distinct_ids("insert_keyframe", ids, id_scratch_);
    if (is_finite(origin_)) return true;
    ks.scan.origin_valid = false;
    ks.scan.points = world_.size();
    return false;
  }

  // The integrator's tests (OctoMap's float norm against max_range, the key range), so the map
  // cloud holds exactly the points that make an occupied update.
  bool within_range(std::size_t j) const {
    return is_finite(world_[j]) &&
           detail::endpoint_fate(map_->grid(), detail::to_point3f(world_[j]),
                                 detail::to_point3f(origin_),
                                 options_.max_range) == detail::EndpointFate::inserted;
  }

  // The loaded keyframe's points as the integrator casts them.
  void take_points(RatedKeyframe& out) const {
    out.origin = detail::to_point3f(origin_);
    out.points.resize(world_.size());
    for (std::size_t j = 0; j < world_.size(); ++j) out.points[j] = detail::to_point3f(world_[j]);
  }

  // Eq 13-14 (or the contextual model's rating) for the loaded keyframe, into `out`.
  void rate_loaded(KeyframeStats& ks, const std::vector<PointEvidence>& evidence,
                   RatedKeyframe& out) {
    if constexpr (contextual) {
      rate_keyframe(ks, evidence, out);
    } else {
      (void)evidence;
      rate_each(ks);
      take_points(out);
      out.ratings = ratings_;
    }
  }

  // The rated keyframe rated_ into the map (insert_keyframe's second half), its scan statistics
  // into ks; a contextual model's scan counts every point of the keyframe, kept or not.
  void integrate_rated(KeyframeStats& ks) {
    if (!ks.scan.origin_valid) return;
    const std::size_t points = ks.scan.points;
    ks.scan = integrate(rated_);
    if constexpr (contextual) ks.scan.points = points;
  }

  // Eq 13, 14 for each endpoint from its s_{p,t}.
  void rate_each(KeyframeStats& ks) {
    ratings_.resize(world_.size());
    const RunningNormal& dist = tracker_.distribution();
    for (std::size_t j = 0; j < world_.size(); ++j) {
      const std::uint64_t id = point_ids_[j];
      if (id == KeyframeUnion::kNoId) {  // beyond max_range (or non-finite): truncated ray only
        ratings_[j] = EndpointRating{0.0f, true};
        continue;
      }
      const double s =
          tracker_.contains(id) ? tracker_.s(id) : std::numeric_limits<double>::quiet_NaN();
      ratings_[j] = model_.rate(s, dist);
      ++ks.rated;
      ks.unrated += std::isnan(s);
      ks.rays += ratings_[j].casts_ray;
    }
  }

  // A contextual model rates the whole keyframe (sensor/contextual_model.hpp); endpoints it rates
  // {0, no ray} stay out of the scan; then it settles the keyframe into edits.
  void rate_keyframe(KeyframeStats& ks, const std::vector<PointEvidence>& evidence,
                     RatedKeyframe& out) {
    const std::size_t n = world_.size();
    ratings_.assign(n, EndpointRating{0.0f, true});  // kNoId: truncated ray only
    const KeyframeView<Key, Tracker> view{keyframe_,  origin_,  world_,   point_ids_,
                                          ids_given_, evidence, tracker_, map_->grid()};
    model_.rate_keyframe(view, ratings_);
    out.origin = detail::to_point3f(origin_);
    for (std::size_t j = 0; j < n; ++j) {
      if (point_ids_[j] != KeyframeUnion::kNoId) {
        ++ks.rated;
        ks.unrated += !tracker_.contains(point_ids_[j]) || std::isnan(tracker_.s(point_ids_[j]));
        ks.rays += ratings_[j].casts_ray;
      }
      if (ratings_[j].casts_ray || ratings_[j].logodds != 0.0f) {
        out.points.push_back(detail::to_point3f(world_[j]));
        out.ratings.push_back(ratings_[j]);
      }
    }
    ks.scan.points = n;
    model_.settle_keyframe(view, ratings_, out.edits);
    ++keyframe_;
  }

  MapperOptions options_;
  std::unique_ptr<map_type> map_;  // on the heap: the integrator points at it, across moves
  Model model_;
  Tracker tracker_;  // detail::NoTracker for a fixed model
  Integrator integrator_;
  // k-NN model: the keyframe being inserted (kept for their memory).
  Mode mode_ = Mode::unset;
  KeyframeUnion union_;
  Point3d origin_;
  std::vector<Point3d> world_, cloud_;
  std::vector<std::uint64_t> cloud_ids_, cloud_map_ids_, point_ids_, id_scratch_;
  std::vector<EndpointRating> ratings_;
  RatedKeyframe rated_;  // insert_keyframe: the keyframe between rating and integration
  bool ids_given_ = false;
  bool without_ids_ = false;  // keyframes without ids kept out of the map cloud (model's choice)
  // Contextual model only.
  std::size_t keyframe_ = 0;  // keyframes rated so far (KeyframeView::index)
};

}  // namespace knnocc
