// expect: needs `EndpointRating rate\(double s, const RunningNormal&\) const`
#include <knnocc/mapper.hpp>
struct Model {
  static constexpr bool uses_map_cloud = true;
  using tracker_type = int;
  float miss_logodds() const { return -0.4f; }
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
