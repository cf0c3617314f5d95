// expect: rates_cloud = true needs `void rate_cloud\(const Point3d& origin
#include <knnocc/mapper.hpp>
struct Model {
  static constexpr bool rates_cloud = true;
  float miss_logodds() const { return -0.4f; }
  knnocc::RayLayers ray_layers() const { return {}; }
};
int main() { knnocc::Mapper<Model> mapper(0.1); }
