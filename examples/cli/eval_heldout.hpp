#pragma once
// knnocc eval --heldout SEQ: the held-out evaluation (eval/heldout.hpp) of one model or of all,
// each map built by Mapper as `knnocc map` builds it (the model's defaults).

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/eval/heldout.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"

namespace knnocc::cli {

/// The keyframes of a sequence whose clouds carry map-point ids, in the world frame, points
/// farther than crop (> 0) from their sensor dropped.
inline std::vector<eval::IdKeyframe> read_id_keyframes(const std::string& path, double crop) {
  const io::Sequence seq = io::Sequence::open(path);
  std::vector<eval::IdKeyframe> out(seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const io::Cloud cloud = seq.load_cloud(i);
    if (cloud.ids.empty())
      throw io::Error(seq.cloud_path(i), "no map-point ids (an `id` vertex property)");
    io::keyframe_to_world(seq.pose(i), cloud, crop, out[i].points, out[i].ids);
    const Eigen::Vector3d& t = seq.pose(i).t;
    out[i].origin = {t.x(), t.y(), t.z()};
  }
  return out;
}

/// The map of keyframes[train] built by Mapper<Model> (as `knnocc map` does: float points for
/// the OctoMap model, ids for the rated ones).
template <class Model>
OccupancyMap<OcKey> map_keyframes(const std::vector<eval::IdKeyframe>& keyframes,
                                  const std::vector<std::size_t>& train, double res,
                                  const Model& model) {
  Mapper<Model> mapper(res, model);
  std::vector<Point3f> f;
  for (const std::size_t i : train) {
    const eval::IdKeyframe& kf = keyframes[i];
    if constexpr (Mapper<Model>::uses_map_cloud) {
      mapper.insert_keyframe(kf.origin, kf.points, kf.ids);
    } else {
      f.clear();
      for (const Point3d& p : kf.points) f.push_back(knnocc::detail::to_point3f(p));
      mapper.insert_keyframe(kf.origin, f);
    }
  }
  return std::move(mapper.map());
}

/// The models `--model` names for the held-out evaluation ("all": every one), calling
/// f(name, model) for each.
template <class F>
void for_each_eval_model(const std::string& which, F&& f) {
  auto run = [&](const char* name, const auto& model) {
    if (which == "all" || which == name) f(name, model);
  };
  run("octomap", OctoMapModel{});
  run("knn", KnnModel{});
  run("robust", RobustModel{});
}

inline int run_eval_heldout(const Args& args) {
  const std::string path = args.str("--heldout");
  const double res = args.number("--res", 0.1);  // each value checked by its declaration
  const double crop = args.number("--crop", -1.0);
  eval::HeldoutOptions opt;
  opt.folds = static_cast<std::size_t>(args.integer("--folds"));
  opt.min_views = static_cast<std::uint32_t>(args.integer("--min-views", opt.min_views));
  opt.end_margin = args.number("--margin");
  const std::string which = args.str("--model");
  const std::vector<eval::IdKeyframe> keyframes = read_id_keyframes(path, crop);
  if (keyframes.size() < opt.folds)
    throw io::Error(path, std::to_string(keyframes.size()) + " keyframes for " +
                              std::to_string(opt.folds) + " folds");
  eval::HeldoutScore octomap;
  for_each_eval_model(which, [&](const char* name, const auto& model) {
    const eval::HeldoutScore s =
        eval::evaluate_heldout(keyframes, opt, [&](const std::vector<std::size_t>& train) {
          return map_keyframes(keyframes, train, res, model);
        });
    if (std::string(name) == "octomap") octomap = s;
    std::printf(
        "heldout %-8s folds %zu points %zu recall %.4f rays %zu seen_through %zu occupied %zu "
        "seen_through_share %.4f",
        name, opt.folds, s.points, s.recall(), s.rays, s.seen_through, s.occupied,
        s.seen_through_share());
    if (octomap.occupied > 0 && octomap.seen_through > 0)
      std::printf(" seen_through/octomap %.1f %%",
                  100.0 * double(s.seen_through) / double(octomap.seen_through));
    std::printf("\n");
    std::fflush(stdout);
  });
  return 0;
}

}  // namespace knnocc::cli
