// expect: a scan integrator for a cloud-rated sensor model needs `ScanStats insert_layered
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
int main() {
  knnocc::Mapper<knnocc::Knn2022Model, knnocc::OcKey, knnocc::detail::NoTracker,
                 knnocc::ScanInserter<knnocc::OcKey, knnocc::Knn2022Model>>
      mapper(0.1);
}
