// The robust model (beyond the paper): Mapper only, as the tool (the live mapper does not take it).

#include <knnocc/sensor/robust_model.hpp>

#include "model_owners.hpp"

namespace knnocc::python {

std::shared_ptr<MapperOwner> make_robust_mapper(double resolution, const ModelOptions& o) {
  RobustModelParams p;
  p.knn = o.knn;
  p.margin_scale = o.margin_scale;
  return std::make_shared<MapperOf<RobustModel>>(resolution, RobustModel(p), o.mapper);
}

}  // namespace knnocc::python
