// The robust model (beyond the paper): Mapper only, as the tool (the live mapper does not take it).

#include <knnocc/sensor/robust_model.hpp>

#include "model_owners.hpp"

namespace knnocc::python {

std::shared_ptr<MapperOwner> make_robust_mapper(double resolution, const ModelOptions& o,
                                                bool wide) {
  RobustModelParams p;
  p.knn = o.knn;
  p.margin_scale = o.margin_scale;
  return make_mapper_of(resolution, RobustModel(p), o.mapper, wide, "robust");
}

}  // namespace knnocc::python
