#pragma once
// knnocc eval --heldout SEQ: the held-out evaluation (eval/heldout.hpp) of one model or of all,
// each map built by Mapper as `knnocc map` builds it (the model's defaults; the 2022 model's from
// its flags). The 2022 model maps the training keyframes uncropped (it cuts at its own inner
// range, as `knnocc map --model knn2022` without --crop), with mu and sigma from a first pass over
// the training keyframes (--stats first-pass) or running ones; every map is scored against the
// same (--crop) held-out keyframes.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/eval/heldout.hpp>
#include <knnocc/eval/id_keyframes.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"
#include "common_options.hpp"

namespace knnocc::cli {

/// The keyframes of a sequence whose clouds carry map-point ids (eval::id_keyframes), each
/// cloud's ids checked to be distinct before any model runs (the models refuse repeated ids too).
inline std::vector<eval::IdKeyframe> read_id_keyframes(const std::string& path, double crop) {
  const io::Sequence seq = io::Sequence::open(path);
  std::vector<std::uint64_t> scratch;
  return eval::id_keyframes(seq, crop, [&](std::size_t i, const io::Cloud& cloud) {
    try {
      knnocc::detail::check_distinct_ids("keyframe", cloud.ids, scratch);
    } catch (const std::invalid_argument& e) {
      throw io::Error(seq.cloud_path(i), e.what());
    }
  });
}

/// io::Error naming the sequence when no fold holds a map point that --min-views of its held-out
/// keyframes observe: with nothing to score, a recall of 0 would read as a result.
inline void check_something_to_score(const std::string& path,
                                     const std::vector<eval::IdKeyframe>& keyframes,
                                     const eval::HeldoutOptions& opt) {
  std::uint32_t most = 0;  // the most held-out keyframes of one fold that observe one map point
  for (std::size_t f = 0; f < opt.folds; ++f)
    for (const auto& e :
         eval::heldout_points(keyframes, eval::fold_indices(keyframes.size(), opt.folds, f, true)))
      most = std::max(most, e.second.views);
  if (most >= opt.min_views) return;
  throw io::Error(path, "nothing to score: no map point is seen by --min-views " +
                            std::to_string(opt.min_views) + " held-out keyframes of one fold (" +
                            std::to_string(keyframes.size()) + " keyframes in --folds " +
                            std::to_string(opt.folds) + ": at most " + std::to_string(most) +
                            " see one point); use fewer --folds or a lower --min-views");
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
      mapper.insert_keyframe(kf.origin, kf.points, kf.ids, kf.evidence);
    } else {
      f.clear();
      for (const Point3d& p : kf.points) f.push_back(knnocc::detail::to_point3f(p));
      mapper.insert_keyframe(kf.origin, f);
    }
  }
  return std::move(mapper.map());
}

/// The 2022 model's map of keyframes[train]: float world points as `knnocc map` gives them, the
/// first pass over the same keyframes when `first_pass`.
inline OccupancyMap<OcKey> map_keyframes_2022(const std::vector<eval::IdKeyframe>& keyframes,
                                              const std::vector<std::size_t>& train, double res,
                                              Knn2022Params p, bool first_pass) {
  std::vector<std::vector<Point3d>> rounded(train.size());
  Knn2022FirstPass pass(p);
  for (std::size_t t = 0; t < train.size(); ++t) {
    for (const Point3d& q : keyframes[train[t]].points) {
      const Point3f f = knnocc::detail::to_point3f(q);
      rounded[t].push_back(Point3d{f.x, f.y, f.z});
    }
    if (first_pass) pass.add(keyframes[train[t]].origin, rounded[t]);
  }
  Mapper<Knn2022Model> mapper(res, Knn2022Model(first_pass ? pass.params() : p));
  for (std::size_t t = 0; t < train.size(); ++t)
    mapper.insert_keyframe(keyframes[train[t]].origin, rounded[t]);
  return std::move(mapper.map());
}

/// The models `--model` names for the held-out evaluation ("all": every one), calling
/// f(name, build) for each, build(train) the map of those keyframes.
template <class F>
void for_each_eval_model(const Args& args, const std::vector<eval::IdKeyframe>& keyframes,
                         const std::vector<eval::IdKeyframe>& whole, double res, F&& f) {
  const std::string which = args.str("--model");
  bool first_pass = true;
  const Knn2022Params p = knn2022_params(args, first_pass);  // checked before any map is built
  auto run = [&](const char* name, const auto& model) {
    if (which == "all" || which == name)
      f(name, [&](const std::vector<std::size_t>& train) {
        return map_keyframes(keyframes, train, res, model);
      });
  };
  run("octomap", OctoMapModel{});
  run("knn", KnnModel{});
  if (which == "all" || which == "knn2022")
    f("knn2022", [&](const std::vector<std::size_t>& train) {
      return map_keyframes_2022(whole, train, res, p, first_pass);
    });
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
  check_something_to_score(path, keyframes, opt);
  // The 2022 model's training keyframes, uncropped (the same ones without --crop).
  std::vector<eval::IdKeyframe> whole;
  if (which == "all" || which == "knn2022")
    whole = crop > 0 ? read_id_keyframes(path, -1.0) : keyframes;
  // What no map can beat on these keyframes (eval/heldout.hpp): computed once, for every model.
  const eval::HeldoutFloor floor = eval::evaluate_heldout_floor(Grid<OcKey>(res), keyframes, opt);
  eval::HeldoutScore octomap;
  for_each_eval_model(args, keyframes, whole, res, [&](const char* name, const auto& build) {
    const eval::HeldoutScore s = eval::evaluate_heldout(keyframes, opt, build);
    if (std::string(name) == "octomap") octomap = s;
    std::printf(
        "heldout %-8s folds %zu points %zu recall %.4f rays %zu seen_through %zu occupied %zu "
        "seen_through_share %.4f floor %zu seen_both %zu",
        name, opt.folds, s.points, s.recall(), s.rays, s.seen_through, s.occupied,
        s.seen_through_share(), floor.fewest_seen_through(s.recalled).value(), s.seen_both);
    if (octomap.occupied > 0 && octomap.seen_through > 0)
      std::printf(" seen_through/octomap %.1f %%",
                  100.0 * double(s.seen_through) / double(octomap.seen_through));
    if (octomap.seen_empty_only() > 0)
      std::printf(" empty_only/octomap %.1f %%",
                  100.0 * double(s.seen_empty_only()) / double(octomap.seen_empty_only()));
    std::printf("\n");
    std::fflush(stdout);
  });
  if (octomap.points > 0 && octomap.seen_through > 0) {
    // The recall goal beside OctoMap's (docs/evaluation.md): its recall less 2 percentage points.
    const double recall = std::max(0.0, octomap.recall() - 0.02);
    const auto need = static_cast<std::size_t>(std::ceil(recall * double(octomap.points) - 1e-9));
    const std::size_t least = floor.fewest_seen_through(need).value();  // OctoMap's maps reach it
    std::printf(
        "heldout_floor recall %.4f (octomap's - 0.02) seen_through %zu (%.1f %% of octomap's)\n",
        recall, least, 100.0 * double(least) / double(octomap.seen_through));
  }
  return 0;
}

}  // namespace knnocc::cli
