#pragma once
// knnocc map --corrections DIR: the map of a sequence folder kept exact while the SLAM system
// corrects its keyframes (LiveMapper, include/knnocc/live/live_mapper.hpp).
//
// DIR holds pose snapshots after_NNNNNN.txt: the trajectory of keyframes 0..NNNNNN (one line
// each, the format of poses.txt) as the SLAM system knew it after keyframe NNNNNN. A snapshot is
// applied right after its keyframe is inserted: every keyframe whose pose differs is re-posed at
// once. Keyframes without a newer snapshot keep the pose of poses.txt. The final map equals the
// map of the same folder with each keyframe's last pose in poses.txt (docs/live_mapping.md).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <new>
#include <string>
#include <utility>
#include <vector>

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

/// DIR's snapshots by keyframe index; io::Error for a file that does not fit `keyframes`.
inline std::map<std::size_t, std::vector<io::Pose>> read_corrections(const std::string& dir,
                                                                     std::size_t keyframes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw io::Error(dir, "not a folder of after_NNNNNN.txt files");
  std::map<std::size_t, std::vector<io::Pose>> out;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("after_", 0) != 0 || e.path().extension() != ".txt") continue;
    const std::string digits = name.substr(6, name.size() - 10);
    if (digits.empty() || digits.size() > 9 ||
        !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
      throw io::Error(e.path().string(), "expected after_NNNNNN.txt (NNNNNN: keyframe index)");
    const std::size_t after = std::stoul(digits);
    if (after >= keyframes)
      throw io::Error(e.path().string(), "keyframe " + std::to_string(after) +
                                             " does not exist (the sequence has " +
                                             std::to_string(keyframes) + ")");
    std::vector<io::Pose> poses = io::read_trajectory(e.path().string());
    if (poses.size() != after + 1)
      throw io::Error(e.path().string(), "expected " + std::to_string(after + 1) +
                                             " poses (keyframes 0.." + std::to_string(after) +
                                             "), found " + std::to_string(poses.size()));
    out.emplace(after, std::move(poses));
  }
  if (ec) throw io::Error(dir, ec.message());
  return out;
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
  const auto corrections = read_corrections(dir, source.size());
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
      if (crop > 0.0) {  // --crop: in the sensor frame, as the from-scratch path
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
      points += pts.size();
      try {
        live.add(i, EigenPose::from(scan.pose), std::move(pts), std::move(ids));
      } catch (const std::invalid_argument& e) {
        throw io::Error(source.path(), "scan " + std::to_string(i) + ": " + e.what());
      }
      const auto snapshot = corrections.find(i);
      if (snapshot == corrections.end()) continue;
      const auto a = std::chrono::steady_clock::now();
      std::vector<std::pair<std::uint64_t, EigenPose>> poses;
      for (std::size_t j = 0; j < snapshot->second.size(); ++j)
        poses.emplace_back(j, EigenPose::from(snapshot->second[j]));
      live.repose(poses);
      reposed += live.last_update().changed;
      correction_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count());
    } catch (const std::bad_alloc&) {  // MemoryLimitError included
      throw out_of_memory(i);
    }
  const auto& map = live.map();
  std::vector<std::string> written;
  if (!out_voxels.empty()) {
    const io::VoxelSelection sel = which == "all"        ? io::VoxelSelection::all
                                   : which == "occupied" ? io::VoxelSelection::occupied
                                                         : io::VoxelSelection::free;
    io::write_voxel_list(out_voxels, io::voxel_records(map, sel));
    written.push_back(out_voxels);
  }
  write_map_outputs(map, args, up_axis(args, up_estimate.result()), model_title(model), written);
  if constexpr (LiveMapper<Model>::uses_map_cloud) {
    const auto& tr = live.tracker();
    std::printf("knn k %zu map_points %zu valid %zu mu %.6f sigma %.6f\n", tr.params().k, tr.size(),
                tr.N(), tr.mu(), tr.sigma());
  }
  std::sort(correction_ms.begin(), correction_ms.end());
  std::printf("corrections %zu reposed_keyframes %zu median_ms %.3f max_ms %.3f\n",
              correction_ms.size(), reposed,
              correction_ms.empty() ? 0.0 : correction_ms[correction_ms.size() / 2],
              correction_ms.empty() ? 0.0 : correction_ms.back());
  const auto counts = map.count_voxels();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", source.size(), points,
              counts.occupied, counts.free, seconds);
  print_written(written);
  return 0;
}

}  // namespace knnocc::cli
