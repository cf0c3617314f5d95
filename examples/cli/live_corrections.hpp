#pragma once
// knnocc map --corrections DIR: the map of a sequence folder kept exact while the SLAM system
// corrects its keyframes (LiveMapper, include/knnocc/live/live_mapper.hpp).
//
// DIR holds pose snapshots after_NNNNNN.txt: the trajectory of keyframes 0..NNNNNN (one line
// each, the format of poses.txt) as the SLAM system knew it after keyframe NNNNNN, read and checked
// against poses.txt by io::read_corrections (io/corrections.hpp). A snapshot is applied right after
// its keyframe is inserted: every keyframe whose pose differs is re-posed at once. Keyframes
// without a newer snapshot keep the pose of poses.txt. The final map equals the map of the same
// folder with each keyframe's last pose in poses.txt (docs/live_mapping.md).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/corrections.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/live/live_mapper.hpp>

#include "args.hpp"
#include "eigen_pose.hpp"
#include "map_outputs.hpp"
#include "resource_limits.hpp"
#include "view_frame.hpp"

namespace knnocc::cli {

/// --crop: drops the points (and their ids, when there are any) farther than `crop` from the
/// sensor, in the sensor frame; crop <= 0 keeps all.
inline void crop_points(std::vector<Point3f>& pts, std::vector<std::uint64_t>& ids, double crop) {
  if (!(crop > 0.0)) return;
  std::size_t kept = 0;
  for (std::size_t j = 0; j < pts.size(); ++j)
    if (std::sqrt(double(pts[j].x) * pts[j].x + double(pts[j].y) * pts[j].y +
                  double(pts[j].z) * pts[j].z) <= crop) {
      if (!ids.empty()) ids[kept] = ids[j];
      pts[kept++] = pts[j];
    }
  pts.resize(kept);
  if (!ids.empty()) ids.resize(kept);
}

/// The corrections line: how many snapshots, the keyframes they re-posed, their times.
inline void print_corrections(std::vector<double>& ms, std::size_t reposed) {
  std::sort(ms.begin(), ms.end());
  std::printf("corrections %zu reposed_keyframes %zu median_ms %.3f max_ms %.3f\n", ms.size(),
              reposed, ms.empty() ? 0.0 : ms[ms.size() / 2], ms.empty() ? 0.0 : ms.back());
}

/// `knnocc map` with --corrections; opt: map_command.hpp's MapOptions.
template <class MapOptions, class Model>
int run_map_corrections(const Args& args, const MapOptions& opt, const Model& model) {
  const std::string &input = opt.input, &out_voxels = opt.out_voxels, &which = opt.which;
  const double crop = opt.crop;
  const auto t0 = std::chrono::steady_clock::now();
  const std::string dir = args.str("--corrections");
  if (!io::is_sequence_dir(input))
    throw io::Error(input, "--corrections needs a sequence folder (poses.txt + clouds/)");
  const io::ScanSource source = io::ScanSource::open(input);
  const auto corrections = io::read_corrections(dir, source.sequence()->poses());
  LiveMapper<Model, OcKey, EigenPose> live(
      opt.res, model, MapperOptions{opt.max_range, opt.discretize, opt.threads, {}});
  live.set_memory_limit(map_memory_share(opt.memory_limit));  // rebuilds and replays included
  auto out_of_memory = [&](std::size_t i) {
    return io::Error(source.path(),
                     "keyframe " + std::to_string(i) + ": " +
                         out_of_memory_text(opt.memory_limit, "mapping or correcting", opt.res));
  };
  std::size_t points = 0, reposed = 0;
  std::vector<double> correction_ms;
  UpEstimator up_estimate;
  for (std::size_t i = 0; i < source.size(); ++i) try {
      io::Scan scan = source.load(i);
      up_estimate.add(scan.pose, scan.cloud.points);
      std::vector<Point3f>& pts = scan.cloud.points;
      std::vector<std::uint64_t>& ids = scan.cloud.ids;
      crop_points(pts, ids, crop);  // as the from-scratch path
      points += pts.size();
      try {
        live.add(i, EigenPose::from(scan.pose), std::move(pts), std::move(ids));
      } catch (const std::invalid_argument& e) {
        throw io::Error(source.sequence()->cloud_path(i), e.what());
      }
      const auto snapshot = corrections.find(i);
      if (snapshot == corrections.end()) continue;
      const auto a = std::chrono::steady_clock::now();
      std::vector<std::pair<std::uint64_t, EigenPose>> poses;
      for (std::size_t j = 0; j < snapshot->second.size(); ++j)  // as poses.txt's rows
        poses.emplace_back(j,
                           EigenPose::from(source.sequence()->scanner_pose(snapshot->second[j])));
      live.repose(poses);
      reposed += live.last_update().changed;
      correction_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
    } catch (const std::bad_alloc&) {  // MemoryLimitError included
      throw out_of_memory(i);
    }
  const auto& map = live.map();
  const ScanStats skipped = live.point_counts();  // at the final poses, as plain `map` counts
  note_skipped_points(input, skipped.nonfinite, skipped.out_of_range, map.grid().max_coord());
  note_empty_map(input, source.size(), points, map, model);
  std::vector<std::string> written;
  if (!out_voxels.empty()) {
    io::write_voxel_list(out_voxels, io::voxel_records(map, voxel_selection(which)));
    written.push_back(out_voxels);
  }
  write_map_outputs(map, args, up_axis(args, up_estimate.result()), model_title(model), written);
  if constexpr (LiveMapper<Model>::uses_map_cloud) {
    const auto& tr = live.tracker();
    std::printf("knn k %zu map_points %zu valid %zu mu %.6f sigma %.6f\n", tr.params().k, tr.size(),
                tr.N(), tr.mu(), tr.sigma());
  }
  print_corrections(correction_ms, reposed);
  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", source.size(), points,
              counts.occupied, counts.free, seconds);
  print_written(written);
  return 0;
}

}  // namespace knnocc::cli
