#pragma once
// knnocc eval --tune-octomap SEQ --reference REF: the OctoMap model at its best on one data set
// (eval/octomap_tuning.hpp), as the authors' 2022 paper compares against it. The reference picks
// the hit / miss / threshold setting with the best F1 of the counting: an oracle baseline, printed
// as such, beside OctoMap's defaults.

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/eval/confusion.hpp>
#include <knnocc/eval/octomap_tuning.hpp>
#include <knnocc/eval/reference.hpp>
#include <knnocc/eval/reference_points.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/mapper.hpp>

#include "args.hpp"
#include "eval_points.hpp"

namespace knnocc::cli {

/// A sequence's clouds in the world frame as `knnocc map` gives them to the OctoMap model (float
/// points, --crop), with their sensor positions.
struct FloatKeyframes {
  std::vector<Point3d> origins;
  std::vector<std::vector<Point3f>> points;
};

inline FloatKeyframes read_float_keyframes(const std::string& path, double crop) {
  const io::Sequence seq = io::Sequence::open(path);
  FloatKeyframes out;
  std::vector<Point3d> world;
  std::vector<std::uint64_t> ids;
  for (std::size_t i = 0; i < seq.size(); ++i) {
    io::keyframe_to_world(seq.pose(i), seq.load_cloud(i), crop, world, ids);
    out.origins.push_back({seq.pose(i).t.x(), seq.pose(i).t.y(), seq.pose(i).t.z()});
    out.points.emplace_back();
    for (const Point3d& p : world) out.points.back().push_back(knnocc::detail::to_point3f(p));
  }
  return out;
}

/// The OctoMap model's map of the keyframes at one setting.
inline OccupancyMap<OcKey> octomap_map(const FloatKeyframes& kfs, double res, double hit,
                                       double miss, double threshold) {
  MapperOptions mo;
  mo.occupancy.occupancy_threshold = logodds(threshold);
  Mapper<OctoMapModel> mapper(res, OctoMapModel::from_probabilities(hit, miss), mo);
  for (std::size_t i = 0; i < kfs.points.size(); ++i)
    mapper.insert_keyframe(kfs.origins[i], kfs.points[i]);
  return std::move(mapper.map());
}

inline void print_setting(const char* name, const eval::OctoMapSetting& s, const char* note) {
  const eval::ConfusionCounts& c = s.counts;
  std::printf(
      "%-9s hit %.2f miss %.2f threshold %.2f tp %zu fp %zu tn %zu fn %zu f1 %.4f mcc %.4f%s\n",
      name, s.hit, s.miss, s.threshold, c.tp, c.fp, c.tn, c.fn, c.f1(), c.mcc(), note);
}

/// The grid against a voxel reference (ShapeVoxels or PointVoxels on the maps' grid): every
/// setting's counts, then the defaults' and the oracle's lines and the five best.
template <class Ref>
eval::OctoMapSetting tune_and_print(const FloatKeyframes& kfs, double res, const Ref& ref) {
  const std::vector<eval::OctoMapSetting> all =
      eval::tune_octomap([&](double hit, double miss, const std::vector<float>& thresholds) {
        return eval::count_confusion(octomap_map(kfs, res, hit, miss, 0.5), ref, thresholds);
      });
  eval::OctoMapSetting defaults;
  for (const eval::OctoMapSetting& s : all)
    if (s.hit == 0.7 && s.miss == 0.4 && s.threshold == 0.5) defaults = s;
  const eval::OctoMapSetting best = eval::best_setting(all);
  print_setting("octomap", defaults, " (OctoMap's defaults)");
  print_setting("octomap*", best, " (an oracle: the reference picked this setting)");
  std::vector<eval::OctoMapSetting> sorted = all;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return a.counts.f1() > b.counts.f1(); });
  for (std::size_t i = 1; i < 5 && i < sorted.size(); ++i) print_setting("next", sorted[i], "");
  return best;
}

inline int run_eval_tune(const Args& args) {
  const std::string seq = args.str("--tune-octomap");
  const std::string ref_path = args.required("--reference");
  const double res = args.number("--res", 0.1);
  const FloatKeyframes kfs = read_float_keyframes(seq, args.number("--crop", -1.0));
  const std::size_t n =
      eval::tuning_hits().size() * eval::tuning_misses().size() * eval::tuning_thresholds().size();
  std::printf(
      "tune-octomap %s at %g m: %zu settings (hit x miss x threshold), each scored against %s by "
      "the authors' counting; the best F1 is an oracle's choice, not a setting a user could pick "
      "without the reference\n",
      seq.c_str(), res, n, ref_path.c_str());
  const Grid<OcKey> grid(res);
  if (!is_point_reference(ref_path)) {
    tune_and_print(kfs, res, eval::ShapeVoxels<OcKey>(eval::read_reference(ref_path), grid));
    return 0;
  }
  const io::Cloud ref = io::read_points(ref_path);
  if (ref.points.empty()) throw io::Error(ref_path, "no points in the reference");
  const eval::OctoMapSetting best =
      tune_and_print(kfs, res, eval::PointVoxels<OcKey>(ref.points, grid));
  // The oracle's map against the points, as `knnocc eval --map ... --reference` prints it.
  std::printf("octomap* against the reference points:\n");
  return run_eval_points(args, octomap_map(kfs, res, best.hit, best.miss, best.threshold),
                         ref_path);
}

}  // namespace knnocc::cli
