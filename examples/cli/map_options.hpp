#pragma once
// What a `knnocc map` run is given and counts, shared by the one-process map (map_command.cpp) and
// the map into tiles (map_tiles.hpp).

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/mapper.hpp>
#include <knnocc/sensor/knn2022_model.hpp>

#include "args.hpp"
#include "map_outputs.hpp"
#include "map_run.hpp"

namespace knnocc::cli {

struct MapOptions {
  std::string input, which, init_map;
  double res = 0, max_range = -1, crop = -1, memory_limit = 0;
  bool discretize = false;
  unsigned threads = 1;
  std::size_t first = 0, count = static_cast<std::size_t>(-1), save_every = 0;
  MapInput scans;             ///< how scans are read (points frame, crop, colours)
  OccupancyParams occupancy;  ///< --clamp
  std::vector<MapFile> files;
  std::optional<std::pair<double, double>> grid_band;  ///< --grid-z
};

/// The file an error in scan i is about: the cloud of a sequence, else the input itself.
inline std::string source_path_for_errors(const std::string& input, std::size_t i) {
  if (io::is_sequence_dir(input)) {
    try {
      return io::Sequence::open(input).cloud_path(i);
    } catch (const std::exception&) {
    }
  }
  return input + (i > 0 ? " (scan " + std::to_string(i) + ")" : "");
}

/// What a run inserted, for the summary lines.
struct MapTotals {
  ScanStats scan;
  std::size_t clouds = 0, rays = 0, rated = 0;
  std::vector<double> keyframe_ms;

  void add(const KeyframeStats& ks) {
    scan.points += ks.scan.points;
    scan.nonfinite += ks.scan.nonfinite;
    scan.out_of_range += ks.scan.out_of_range;
    rays += ks.rays;
    rated += ks.rated;
    ++clouds;
  }
};

/// One past the last cloud the run maps (--first, --count); UsageError when --first is past the
/// input's end.
inline std::size_t last_cloud(const MapOptions& opt, const io::ScanSource& source) {
  if (opt.first > source.size() || (opt.first == source.size() && source.size() > 0))
    throw UsageError("--first " + std::to_string(opt.first) + ": " + opt.input + " has " +
                     std::to_string(source.size()) + " clouds");
  return opt.first + std::min(opt.count, source.size() - opt.first);
}

/// The model's line before the summary: the k-NN statistics (k-NN and robust models, with the
/// dense-input warning of the k-NN model) or the 2022 model's statistics; nothing for OctoMap's.
template <class MapperT>
void print_model_line(const MapperT& mapper, const MapOptions& opt, MapTotals& totals) {
  const ScanStats& total = totals.scan;
  if constexpr (MapperT::uses_map_cloud) {
    const auto& tr = mapper.tracker();
    // Dense input (depth camera, LiDAR): the paper's s-rating removes far, sparser surfaces.
    const std::size_t per_cloud = totals.clouds ? total.points / totals.clouds : 0;
    if constexpr (!MapperT::contextual)
      if (totals.clouds > 0 && tr.N() > 0 && (tr.mu() < 0.5 * opt.res || per_cloud > 20000))
        std::fprintf(stderr,
                     "knnocc map: %s: warning: dense input (mean k-NN distance %.3g m at --res %g, "
                     "%zu points per cloud): the k-NN model removes far, sparser surfaces of "
                     "dense clouds; --model octomap (or robust) keeps them\n",
                     opt.input.c_str(), tr.mu(), opt.res, per_cloud);
    std::vector<double>& ms = totals.keyframe_ms;
    std::sort(ms.begin(), ms.end());
    std::printf(
        "knn k %zu map_points %zu valid %zu mu %.6f sigma %.6f rays %zu of %zu "
        "median_keyframe_ms %.3f\n",
        tr.params().k, tr.size(), tr.N(), tr.mu(), tr.sigma(), totals.rays, totals.rated,
        ms.empty() ? 0.0 : ms[ms.size() / 2]);
  } else if constexpr (MapperT::rates_cloud) {
    const Knn2022Model& m = mapper.model();
    std::vector<double>& ms = totals.keyframe_ms;
    std::sort(ms.begin(), ms.end());
    std::printf(
        "knn2022 k %zu stats %s mu %.6f sigma %.6f inner %zu of %zu median_keyframe_ms %.3f\n",
        m.params().k, m.params().fixed_statistics ? "first-pass" : "online", m.mu(), m.sigma(),
        totals.rated, total.points, ms.empty() ? 0.0 : ms[ms.size() / 2]);
  }
}

}  // namespace knnocc::cli
