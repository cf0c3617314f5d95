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
#include "map_run.hpp"
#include "resource_limits.hpp"
#include "view_frame.hpp"

namespace knnocc::cli {

/// The corrections line: how many snapshots, the keyframes they re-posed, their times.
inline void print_corrections(std::vector<double>& ms, std::size_t reposed) {
  std::sort(ms.begin(), ms.end());
  std::printf("corrections %zu reposed_keyframes %zu median_ms %.3f max_ms %.3f\n", ms.size(),
              reposed, ms.empty() ? 0.0 : ms[ms.size() / 2], ms.empty() ? 0.0 : ms.back());
}

/// Re-poses the keyframes of a snapshot (rows as poses.txt's); returns how many changed.
template <class Live>
std::size_t apply_snapshot(Live& live, const io::Sequence& seq,
                           const std::vector<io::Pose>& snapshot) {
  std::vector<std::pair<std::uint64_t, EigenPose>> poses;
  for (std::size_t j = 0; j < snapshot.size(); ++j)
    poses.emplace_back(j, EigenPose::from(seq.scanner_pose(snapshot[j])));
  live.repose(poses);
  return live.last_update().changed;
}

/// The keyframes' colours (`colors[i]` for keyframe i) with their final poses: the voxel colours
/// a from-scratch map of the final trajectory gets.
template <class Live>
void add_final_colors(const Live& live, const std::vector<std::vector<knnocc::Rgb>>& colors,
                      MapRun& run) {
  std::vector<Point3d> world;
  for (const auto& kf : live.keyframes().frames()) {
    if (kf.id >= colors.size() || colors[kf.id].empty()) continue;
    world.clear();
    for (const Point3f& p : kf.points)
      world.push_back(pose_traits<EigenPose>::to_world(kf.pose, p));
    run.add_colors(pose_traits<EigenPose>::origin(kf.pose), world, colors[kf.id]);
  }
}

/// The notes and summary lines of a corrected run (skipped points, the k-NN line, the
/// corrections, the counts).
template <class Live, class Model>
void report_corrections(const Live& live, const Model& model, const MapRun& run,
                        std::vector<double>& correction_ms, std::size_t reposed, std::size_t clouds,
                        std::chrono::steady_clock::time_point t0) {
  const auto& map = live.map();
  const ScanStats skipped = live.point_counts();  // at the final poses, as plain `map` counts
  const std::string& input = run.input().path;
  note_skipped_points(input, skipped.nonfinite, skipped.out_of_range, map.grid().max_coord(),
                      map.grid().resolution());
  note_empty_map(input, clouds, run.points(), map.count_voxels().known(), model);
  if constexpr (Live::uses_map_cloud) {
    const auto& tr = live.tracker();
    std::printf("knn k %zu map_points %zu valid %zu mu %.6f sigma %.6f\n", tr.params().k, tr.size(),
                tr.N(), tr.mu(), tr.sigma());
  }
  print_corrections(correction_ms, reposed);
  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", clouds, run.points(),
              counts.occupied, counts.free, seconds);
}

/// `knnocc map` with --corrections; opt: map_command.cpp's MapOptions. write_files(map, run,
/// title, written, notes) writes the map files and collects what to print after the summary.
template <class MapOptions, class Model, class WriteFiles>
int run_map_corrections(const Args& args, const MapOptions& opt, const Model& model,
                        WriteFiles&& write_files) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!io::is_sequence_dir(opt.input))
    throw io::Error(opt.input, "--corrections needs a sequence folder (poses.txt + clouds/)");
  const io::ScanSource source = io::ScanSource::open(opt.input);
  const io::Sequence& seq = *source.sequence();
  const auto corrections = io::read_corrections(args.str("--corrections"), seq.poses());
  LiveMapper<Model, OcKey, EigenPose> live(
      opt.res, model, MapperOptions{opt.max_range, opt.discretize, opt.threads, opt.occupancy});
  live.set_memory_limit(map_memory_share(opt.memory_limit));  // rebuilds and replays included
  MapRun run(opt.scans, opt.res);
  std::vector<std::vector<knnocc::Rgb>> colors(source.size());  // applied with the final poses
  std::size_t reposed = 0;
  std::vector<double> correction_ms;
  for (std::size_t i = 0; i < source.size(); ++i) try {
      io::Scan scan = source.load(i);
      run.prepare(scan, live.map().grid(), seq.cloud_path(i));
      colors[i] = std::move(scan.cloud.colors);
      try {
        live.add(i, EigenPose::from(scan.pose), std::move(scan.cloud.points),
                 std::move(scan.cloud.ids));
      } catch (const std::invalid_argument& e) {
        throw io::Error(seq.cloud_path(i), e.what());
      }
      const auto snapshot = corrections.find(i);
      if (snapshot == corrections.end()) continue;
      const auto a = std::chrono::steady_clock::now();
      reposed += apply_snapshot(live, seq, snapshot->second);
      correction_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
    } catch (const std::bad_alloc&) {  // MemoryLimitError included
      throw io::Error(source.path(),
                      "keyframe " + std::to_string(i) + ": " +
                          out_of_memory_text(opt.memory_limit, "mapping or correcting", opt.res));
    }
  add_final_colors(live, colors, run);
  std::vector<std::string> written, notes;
  write_files(live.map(), run, std::string(model_title(model)), written, notes);
  report_corrections(live, model, run, correction_ms, reposed, source.size(), t0);
  for (const std::string& n : notes) std::printf("%s\n", n.c_str());
  print_written(written);
  return 0;
}

}  // namespace knnocc::cli
