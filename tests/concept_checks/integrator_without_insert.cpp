// expect: a scan integrator for a fixed sensor model needs `ScanStats insert_point_cloud
#include <knnocc/mapper.hpp>
struct Integrator {
  Integrator(knnocc::OccupancyMap<knnocc::OcKey>&, const knnocc::OctoMapModel&, unsigned) {}
};
int main() {
  knnocc::Mapper<knnocc::OctoMapModel, knnocc::OcKey, knnocc::detail::NoTracker, Integrator> m(0.1);
}
