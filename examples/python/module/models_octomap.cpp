// OctoMap's model: Python's OccupancyMap (a map with its scan inserter), Mapper and LiveMapper.

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/sensor/octomap_model.hpp>

#include "model_owners.hpp"

namespace knnocc::python {

namespace {

class MapWithInserter final : public MapObject {
 public:
  MapWithInserter(Map map, double prob_hit, double prob_miss)
      : MapObject(prob_hit, prob_miss),
        map_(std::move(map)),
        inserter_(map_, OctoMapModel::from_probabilities(prob_hit, prob_miss)) {}
  const Map& map() const override { return map_; }
  void set_memory_limit(std::size_t bytes) override { map_.set_memory_limit(bytes); }
  void insert_point_cloud(const Point3d& origin, const PointsView& points, double max_range,
                          unsigned threads, bool discretize) override {
    if (inserter_.threads() != threads) inserter_.set_threads(threads);
    points.visit([&](const auto& span) {
      inserter_.insert_point_cloud(origin, span, max_range, discretize);
    });
  }

 private:
  Map map_;
  ScanInserter<OcKey, OctoMapModel> inserter_;  // points at map_: this object never moves
};

}  // namespace

std::shared_ptr<MapObject> make_map_object(Map map, double prob_hit, double prob_miss) {
  return std::make_shared<MapWithInserter>(std::move(map), prob_hit, prob_miss);
}

std::shared_ptr<MapperOwner> make_octomap_mapper(double resolution, const ModelOptions& o,
                                                 bool wide) {
  return make_mapper_of(resolution, OctoMapModel::from_probabilities(o.prob_hit, o.prob_miss),
                        o.mapper, wide, "octomap");
}

std::shared_ptr<LiveOwner> make_octomap_live(double resolution, const ModelOptions& o) {
  return std::make_shared<LiveOf<OctoMapModel>>(
      resolution, OctoMapModel::from_probabilities(o.prob_hit, o.prob_miss), o.mapper);
}

}  // namespace knnocc::python
