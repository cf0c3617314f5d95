// The k-NN inverse sensor model next to OctoMap's: the same keyframes through Mapper<KnnModel>
// and Mapper<OctoMapModel> (one type apart), here from the built-in simulated tree scene.
#include <cstdio>

#include <knnocc/eval/metrics.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sim/tree_scene.hpp>

template <class Model>
void run(const char* name, const knnocc::sim::TreeScene& scene,
         const std::vector<knnocc::sim::SimKeyframe>& keyframes, Model model) {
  knnocc::Mapper<Model> mapper(0.1, model);
  knnocc::sim::map_keyframes(mapper, keyframes, /*crop=*/4.0);  // the paper keeps 4 m
  const knnocc::eval::Metrics m = knnocc::eval::evaluate(mapper.map(), scene.reference());
  std::printf("%-8s occupied %4zu  in shell %4zu  irrelevant %3zu  free inside objects %4zu\n",
              name, m.occupied, m.in_shell, m.irrelevant, m.free_inside);
}

int main() {
  knnocc::sim::TreeScene scene;  // seed 1, 60 keyframes around a potted tree
  const auto keyframes = scene.keyframes();
  run("octomap", scene, keyframes, knnocc::OctoMapModel{});
  knnocc::KnnModelParams p;  // the documented defaults; change k, w, P_u, P_w, s_limit here
  run("knn", scene, keyframes, knnocc::KnnModel(p));
  return 0;
}
