#pragma once
// The owners of owners.hpp for one sensor model: Mapper<Model> and LiveMapper<Model>. Included
// by models_*.cpp only, one model per translation unit.

#include <utility>
#include <vector>

#include "owners.hpp"

namespace knnocc::python {

template <class Model>
class MapperOf final : public MapperOwner {
 public:
  MapperOf(double resolution, Model model, const MapperOptions& o)
      : mapper_(resolution, std::move(model), o) {}
  const Map& map() const override { return mapper_.map(); }
  void set_memory_limit(std::size_t bytes) override { mapper_.map().set_memory_limit(bytes); }
  void insert_keyframe(const Point3d& origin, const PointsView& points,
                       const std::vector<std::uint64_t>& ids,
                       const std::vector<PointEvidence>& evidence) override {
    if constexpr (Mapper<Model>::rates_cloud) {  // float world points, as the tool gives them
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
    if constexpr (Mapper<Model>::uses_map_cloud)
      return tracker_stats(mapper_.tracker());
    else
      return {};
  }

 private:
  Mapper<Model> mapper_;         // not movable: this object is made in place and never moves
  std::vector<Point3f> floats_;  // the 2022 model's float points
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

}  // namespace knnocc::python
