#pragma once
// The owners of owners.hpp for one sensor model: Mapper<Model> and LiveMapper<Model>. Included
// by models_*.cpp only, one model per translation unit.

#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <knnocc/io/trajectory.hpp>
#include <knnocc/tiles/rating_pass.hpp>

#include "owners.hpp"

namespace knnocc::python {

/// Mapper<Model, Key>: OctoMap's keys, or 21-bit keys (Mapper(..., wide=True)), whose map is
/// shown at OctoMap's keys where it fits (map(): made again after each insert, std::out_of_range
/// beyond OctoMap's key range) and written whole as a tile set (write_tiles).
template <class Model, class Key = OcKey>
class MapperOf final : public MapperOwner {
 public:
  MapperOf(double resolution, Model model, const MapperOptions& o, std::string name)
      : mapper_(resolution, std::move(model), o), name_(std::move(name)) {}
  const Map& map() const override {
    if constexpr (std::is_same_v<Key, OcKey>) {
      return mapper_.map();
    } else {
      if (!narrow_) narrow_ = narrow_copy(mapper_.map());
      return *narrow_;
    }
  }
  void set_memory_limit(std::size_t bytes) override { mapper_.map().set_memory_limit(bytes); }
  std::size_t memory_limit() const override { return mapper_.map().memory_limit(); }
  bool wide() const override { return !std::is_same_v<Key, OcKey>; }
  void insert_keyframe(const Point3d& origin, const PointsView& points,
                       const std::vector<std::uint64_t>& ids,
                       const std::vector<PointEvidence>& evidence) override {
    narrow_.reset();
    if constexpr (Mapper<Model, Key>::rates_cloud) {  // float world points, as the tool gives them
      floats_.clear();
      points.visit([&](const auto& span) {
        for (std::size_t i = 0; i < span.size(); ++i)
          floats_.push_back(knnocc::detail::to_point3f(span[i]));
      });
      mapper_.insert_keyframe(origin, floats_);
    } else {
      points.visit([&](const auto& span) { mapper_.insert_keyframe(origin, span, ids, evidence); });
    }
  }
  TrackerStats statistics() const override {
    if constexpr (Mapper<Model, Key>::uses_map_cloud)
      return tracker_stats(mapper_.tracker());
    else
      return {};
  }
  std::size_t write_tiles(const std::string& dir, int depth) const override {
    return write_map_tiles(mapper_.map(), mapper_.integration(), name_, dir, depth);
  }
  tiles::RatingTotals rate_sequence(const io::ScanSource& source, const std::string& rated,
                                    double crop, bool world_points, std::size_t first,
                                    std::size_t last, std::vector<double>& rating_ms) override {
    tiles::RatedStoreWriter<Key> out(rated, mapper_.map().resolution());
    auto prepare = [&](io::Scan& scan, std::size_t) {
      if (world_points) io::transform_to_sensor(scan.pose, scan.cloud.points);
      io::crop_cloud(scan.cloud, crop);
    };
    auto rated_one = [&](std::size_t, const KeyframeStats&, double ms) { rating_ms.push_back(ms); };
    return tiles::rate_sequence(source, first, last, mapper_, out, prepare, rated_one);
  }

 private:
  Mapper<Model, Key> mapper_;          // not movable: this object is made in place and never moves
  std::string name_;                   // the model's name (a tile set's index says it)
  mutable std::optional<Map> narrow_;  // a wide map at OctoMap's keys, made when asked
  std::vector<Point3f> floats_;        // the 2022 model's float points
};

template <class Model>
class LiveOf final : public LiveOwner {
 public:
  LiveOf(double resolution, Model model, const MapperOptions& o)
      : live_(resolution, std::move(model), o) {}
  const Map& map() const override { return live_.map(); }
  void set_memory_limit(std::size_t bytes) override { live_.set_memory_limit(bytes); }
  void add(std::uint64_t id, const Pose& pose, std::vector<Point3f> points,
           std::vector<std::uint64_t> ids) override {
    live_.add(id, pose, std::move(points), std::move(ids));
  }
  void repose(const std::vector<std::pair<std::uint64_t, Pose>>& poses) override {
    live_.repose(poses);
  }
  void remove(const std::vector<std::uint64_t>& ids) override { live_.remove(ids); }
  std::size_t size() const override { return live_.size(); }
  bool contains(std::uint64_t id) const override { return live_.contains(id); }
  LiveUpdate last_update() const override { return live_.last_update(); }
  TrackerStats statistics() const override {
    if constexpr (LiveMapper<Model, OcKey, Pose>::uses_map_cloud)
      return tracker_stats(live_.tracker());
    else
      return {};
  }

 private:
  LiveMapper<Model, OcKey, Pose> live_;
};

/// A Mapper of `Model`, with OctoMap's keys or 21-bit ones.
template <class Model>
std::shared_ptr<MapperOwner> make_mapper_of(double resolution, Model model, const MapperOptions& o,
                                            bool wide, const char* name) {
  if (wide)
    return std::make_shared<MapperOf<Model, WideKey>>(resolution, std::move(model), o, name);
  return std::make_shared<MapperOf<Model>>(resolution, std::move(model), o, name);
}

}  // namespace knnocc::python
