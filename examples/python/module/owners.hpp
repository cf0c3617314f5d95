#pragma once
// What the module's Python objects hold, without pybind11: a map of its own (OccupancyMap), a
// Mapper or a LiveMapper, each behind one interface, so that each sensor model's templates are
// instantiated in a translation unit of their own (models_*.cpp) and compile in parallel.
//
// Every owner carries the Guard of its map: a Mapper's map shown to Python (Mapper.map) is the
// same object as far as the one-writer rule goes.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/core/key.hpp>
#include <knnocc/core/log_odds.hpp>
#include <knnocc/core/point3.hpp>
#include <knnocc/core/point_evidence.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/live/live_mapper.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/tiles/rated_store.hpp>

#include "../../cli/eigen_pose.hpp"
#include "guard.hpp"
#include "points.hpp"

namespace knnocc::python {

using Map = OccupancyMap<OcKey>;
using Pose = cli::EigenPose;

/// Everything Mapper and LiveMapper take besides the resolution (Python keyword arguments).
struct ModelOptions {
  double prob_hit = 0.7, prob_miss = 0.4;  ///< OctoMap model
  KnnModelParams knn;                      ///< k-NN and robust models
  double margin_scale = 2.0;               ///< robust model (RobustModelParams)
  Knn2022Params knn2022;                   ///< the authors' 2022 model
  MapperOptions mapper;                    ///< max_range, discretize, threads, clamping
};

/// Clamping thresholds given as probabilities in (0, 1), as OctoMap's setClampingThres*.
inline OccupancyParams occupancy_params(double clamp_min, double clamp_max) {
  if (!(clamp_min > 0.0 && clamp_min < 1.0) || !(clamp_max > 0.0 && clamp_max < 1.0))
    throw std::invalid_argument("clamp_min and clamp_max must be probabilities in (0, 1)");
  OccupancyParams p;
  p.clamp_min = logodds(clamp_min);
  p.clamp_max = logodds(clamp_max);
  p.validate();
  return p;
}

/// The k-NN statistics of a mapper's map point cloud (k-NN and robust models).
struct TrackerStats {
  bool kept = false;  ///< false for the OctoMap model
  std::size_t k = 0, map_points = 0, valid = 0;
  double mu = 0, sigma = 0;
};

class MapOwner {
 public:
  MapOwner() = default;
  MapOwner(const MapOwner&) = delete;
  MapOwner& operator=(const MapOwner&) = delete;
  virtual ~MapOwner() = default;
  virtual const Map& map() const = 0;
  virtual void set_memory_limit(std::size_t bytes) = 0;
  virtual std::size_t memory_limit() const { return map().memory_limit(); }
  Guard guard;
};

/// A map of its own with OctoMap's model and a scan inserter (Python's OccupancyMap).
class MapObject : public MapOwner {
 public:
  MapObject(double prob_hit, double prob_miss) : prob_hit_(prob_hit), prob_miss_(prob_miss) {}
  /// ScanInserter::insert_point_cloud with `threads` threads.
  virtual void insert_point_cloud(const Point3d& origin, const PointsView& points, double max_range,
                                  unsigned threads, bool discretize) = 0;
  double prob_hit() const { return prob_hit_; }
  double prob_miss() const { return prob_miss_; }

 private:
  double prob_hit_, prob_miss_;
};
/// std::invalid_argument on bad probabilities.
std::shared_ptr<MapObject> make_map_object(Map map, double prob_hit, double prob_miss);

/// Mapper<Model, Key> for one of the four models, with OctoMap's keys or 21-bit ones.
class MapperOwner : public MapOwner {
 public:
  /// `ids` and `evidence` (the SLAM counters) each empty or one per point.
  virtual void insert_keyframe(const Point3d& origin, const PointsView& points,
                               const std::vector<std::uint64_t>& ids,
                               const std::vector<PointEvidence>& evidence) = 0;
  virtual TrackerStats statistics() const = 0;
  /// 21-bit keys (map() is then the map at OctoMap's keys, or std::domain_error beyond them).
  virtual bool wide() const = 0;
  /// The map as a tile set in the new folder `dir` (tiles at `depth`); returns the tiles.
  virtual std::size_t write_tiles(const std::string& dir, int depth) const = 0;
  /// The rating pass of `knnocc map --out-tiles` (tiles/rating_pass.hpp) over scans [first,
  /// last) of `source` into the folder of rated keyframes `rated`, each scan prepared as the tool
  /// prepares it (world-frame points moved into the sensor frame, then --crop); this mapper's
  /// map stays empty. `rating_ms` gets each keyframe's rating time.
  virtual tiles::RatingTotals rate_sequence(const io::ScanSource& source, const std::string& rated,
                                            double crop, bool world_points, std::size_t first,
                                            std::size_t last, std::vector<double>& rating_ms) = 0;
};
std::shared_ptr<MapperOwner> make_octomap_mapper(double resolution, const ModelOptions& o,
                                                 bool wide);
std::shared_ptr<MapperOwner> make_knn_mapper(double resolution, const ModelOptions& o, bool wide);
std::shared_ptr<MapperOwner> make_robust_mapper(double resolution, const ModelOptions& o,
                                                bool wide);
std::shared_ptr<MapperOwner> make_knn2022_mapper(double resolution, const ModelOptions& o,
                                                 bool wide);

/// The 2022 model's first pass over scans [first, last) of `source`, each prepared and moved to
/// the world frame as `knnocc map --model knn2022` does (its default --stats first-pass): `p`
/// with the statistics filled in.
Knn2022Params knn2022_first_pass(const io::ScanSource& source, const Knn2022Params& p, double crop,
                                 bool world_points, std::size_t first, std::size_t last);

/// A map of 21-bit keys at OctoMap's keys (std::domain_error naming its extent when it reaches
/// beyond them).
template <class Key>
Map narrow_copy(const OccupancyMap<Key>& wide) {
  constexpr std::int64_t shift = Key::center - OcKey::center;
  Map out(wide.resolution(), wide.params());
  std::int64_t reach = 0;
  wide.for_each_voxel([&](const Key& k, float) {
    for (int a = 0; a < 3; ++a)
      reach =
          std::max({reach, Key::center - std::int64_t{k[a]}, std::int64_t{k[a]} + 1 - Key::center});
  });
  if (reach > OcKey::center)
    throw std::domain_error("the map reaches " + std::to_string(double(reach) * wide.resolution()) +
                            " m from its origin, beyond the +-" +
                            std::to_string(32768.0 * wide.resolution()) +
                            " m of OctoMap's keys: write it as a tile set (Mapper.write_tiles)");
  wide.for_each_voxel([&](const Key& k, float v) {
    out.set(
        OcKey(static_cast<std::uint16_t>(k[0] - shift), static_cast<std::uint16_t>(k[1] - shift),
              static_cast<std::uint16_t>(k[2] - shift)),
        v);
  });
  return out;
}

/// `map` as a tile set in the new folder `dir` (an existing tile set is replaced): its tiles at
/// `depth` and an index with the mapper's integration constants; returns the tiles written.
template <class Key>
std::size_t write_map_tiles(const OccupancyMap<Key>& map, const IntegrationParams& integration,
                            const std::string& model, const std::string& dir, int depth);

/// LiveMapper<Model, OcKey, Pose> for the OctoMap and k-NN models.
class LiveOwner : public MapOwner {
 public:
  virtual void add(std::uint64_t id, const Pose& pose, std::vector<Point3f> points,
                   std::vector<std::uint64_t> ids) = 0;
  virtual void repose(const std::vector<std::pair<std::uint64_t, Pose>>& poses) = 0;
  virtual void remove(const std::vector<std::uint64_t>& ids) = 0;
  virtual std::size_t size() const = 0;
  virtual bool contains(std::uint64_t id) const = 0;
  virtual LiveUpdate last_update() const = 0;
  virtual TrackerStats statistics() const = 0;
};
std::shared_ptr<LiveOwner> make_octomap_live(double resolution, const ModelOptions& o);
std::shared_ptr<LiveOwner> make_knn_live(double resolution, const ModelOptions& o);

/// The statistics of a KnnTracker.
template <class Tracker>
TrackerStats tracker_stats(const Tracker& t) {
  TrackerStats s;
  s.kept = true;
  s.k = t.params().k;
  s.map_points = t.size();
  s.valid = t.N();
  s.mu = t.mu();
  s.sigma = t.sigma();
  return s;
}

}  // namespace knnocc::python
