// The paper's k-NN model: Mapper and LiveMapper.

#include <knnocc/sensor/knn_model.hpp>

#include "model_owners.hpp"

namespace knnocc::python {

std::shared_ptr<MapperOwner> make_knn_mapper(double resolution, const ModelOptions& o, bool wide) {
  return make_mapper_of(resolution, KnnModel(o.knn), o.mapper, wide, "knn");
}

std::shared_ptr<LiveOwner> make_knn_live(double resolution, const ModelOptions& o) {
  return std::make_shared<LiveOf<KnnModel>>(resolution, KnnModel(o.knn), o.mapper);
}

}  // namespace knnocc::python
