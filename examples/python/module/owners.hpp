#pragma once
// What the module's Python objects hold, without pybind11: a map of its own (OccupancyMap), a
// Mapper or a LiveMapper, each behind one interface, so that each sensor model's templates are
// instantiated in a translation unit of their own (models_*.cpp) and compile in parallel.
//
// Every owner carries the Guard of its map: a Mapper's map shown to Python (Mapper.map) is the
// same object as far as the one-writer rule goes.

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
#include <knnocc/live/live_mapper.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>

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

/// Mapper<Model> for one of the four models.
class MapperOwner : public MapOwner {
 public:
  /// `ids` and `evidence` (the SLAM counters) each empty or one per point.
  virtual void insert_keyframe(const Point3d& origin, const PointsView& points,
                               const std::vector<std::uint64_t>& ids,
                               const std::vector<PointEvidence>& evidence) = 0;
  virtual TrackerStats statistics() const = 0;
};
std::shared_ptr<MapperOwner> make_octomap_mapper(double resolution, const ModelOptions& o);
std::shared_ptr<MapperOwner> make_knn_mapper(double resolution, const ModelOptions& o);
std::shared_ptr<MapperOwner> make_robust_mapper(double resolution, const ModelOptions& o);
std::shared_ptr<MapperOwner> make_knn2022_mapper(double resolution, const ModelOptions& o);

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
