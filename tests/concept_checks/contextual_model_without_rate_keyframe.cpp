// expect: contextual sensor model needs `template <class Key, class Tracker> void rate_keyframe
#include <knnocc/knn/tracker.hpp>
#include <knnocc/mapper.hpp>
struct Model {
  static constexpr bool uses_map_cloud = true;
  using tracker_type = knnocc::KnnTracker<>;
  float miss_logodds() const { return -0.4f; }
  template <class Key, class Tracker>
  void settle_keyframe(const knnocc::KeyframeView<Key, Tracker>&,
                       const std::vector<knnocc::EndpointRating>&, std::vector<knnocc::MapEdit>&) {}
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
