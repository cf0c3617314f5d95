// expect: needs a tracker: declare `using tracker_type = ...`
#include <knnocc/mapper.hpp>
struct Model {
  static constexpr bool uses_map_cloud = true;
  float miss_logodds() const { return -0.4f; }
  knnocc::EndpointRating rate(double, const knnocc::RunningNormal&) const { return {}; }
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
