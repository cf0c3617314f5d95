// expect: a tracker needs `bool contains\(std::uint64_t\) const`, `double s\(std::uint64_t\) const`
// and `const RunningNormal& distribution\(\) const`
#include <knnocc/mapper.hpp>
struct Model {
  static constexpr bool uses_map_cloud = true;
  float miss_logodds() const { return -0.4f; }
  knnocc::EndpointRating rate(double, const knnocc::RunningNormal&) const { return {}; }
};
struct Tracker {
  knnocc::TrackerUpdate apply(const knnocc::ChangeSet&) { return {}; }
  bool contains(std::uint64_t) const { return false; }
  double s(std::uint64_t) const { return 0; }
};
int main() { knnocc::Mapper<Model, knnocc::OcKey, Tracker> mapper(0.1); }
