#pragma once
// The map files `knnocc map` (and `knnocc convert`) can write besides --out-voxels:
// OctoMap trees for octovis/octomap_server, PLY voxels for CloudCompare/MeshLab, a PNG picture,
// a 3D web page.

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/voxel_export.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/octomap_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"
#include "map_picture.hpp"
#include "view_page.hpp"

namespace knnocc::cli {

inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// Checks the output options before any work (octovis picks the reader by the extension).
inline void check_map_outputs(const Args& args) {
  if (args.has("--out-bt") && lower_extension(args.str("--out-bt")) != ".bt")
    throw UsageError("--out-bt needs a file name ending in .bt, got '" + args.str("--out-bt") +
                     "'");
  if (args.has("--out-ot") && lower_extension(args.str("--out-ot")) != ".ot")
    throw UsageError("--out-ot needs a file name ending in .ot, got '" + args.str("--out-ot") +
                     "'");
  if (args.has("--up")) parse_up_axis(args.str("--up"));
  if (args.has("--out-png") && lower_extension(args.str("--out-png")) != ".png")
    throw UsageError("--out-png writes PNG only and needs a file name ending in .png, got '" +
                     args.str("--out-png") + "'");
  if ((args.flag("--ply-cubes") || args.flag("--ply-free")) && !args.has("--out-ply"))
    throw UsageError("--ply-cubes and --ply-free need --out-ply");
}

/// --voxels / --out-voxels' selection by name: occupied, free or all.
inline io::VoxelSelection voxel_selection(const std::string& which) {
  return which == "occupied" ? io::VoxelSelection::occupied
         : which == "free"   ? io::VoxelSelection::free
                             : io::VoxelSelection::all;
}

/// The model's name in titles and pictures.
inline const char* model_title(const OctoMapModel&) { return "OctoMap model"; }
inline const char* model_title(const KnnModel&) { return "k-NN model"; }
inline const char* model_title(const RobustModel&) { return "robust model"; }

/// The notes (stderr) on points a map holds no update from: NaN/Inf coordinates, points outside
/// the key range (|c| >= max_coord), e.g. moved there by a correction.
inline void note_skipped_points(const std::string& input, std::size_t nonfinite,
                                std::size_t out_of_range, double max_coord) {
  if (nonfinite)
    std::fprintf(stderr, "knnocc map: %s: skipped %zu points with NaN/Inf coordinates\n",
                 input.c_str(), nonfinite);
  if (out_of_range)
    std::fprintf(stderr,
                 "knnocc map: %s: skipped %zu points outside the map's key range (|c| >= %g m at "
                 "--res %g); use a coarser --res (the library's WideKey maps reach 64x farther)\n",
                 input.c_str(), out_of_range, max_coord, max_coord / 32768.0);
}

/// A warning (stderr) when clouds were read and the map holds no voxel: never silent.
template <class Model>
void note_empty_map(const std::string& input, std::size_t clouds, std::size_t points,
                    const OccupancyMap<OcKey>& map, const Model&) {
  if (clouds == 0 || map.count_voxels().known() > 0) return;
  const char* why = std::is_same_v<Model, RobustModel>
                        ? "; the robust model adds a map point's evidence only while it believes "
                          "the point real (docs/robust_model.md)"
                        : "";
  std::fprintf(stderr,
               "knnocc map: %s: warning: the map is empty: the %zu points of %zu clouds updated no "
               "voxel%s\n",
               input.c_str(), points, clouds, why);
}

/// Prints `wrote A, B, ...` (nothing when no file was written).
inline void print_written(const std::vector<std::string>& written) {
  if (written.empty()) return;
  std::string line = "wrote";
  for (std::size_t i = 0; i < written.size(); ++i) line += (i ? ", " : " ") + written[i];
  std::printf("%s\n", line.c_str());
}

/// --up if given, else `estimated`.
inline UpAxis up_axis(const Args& args, UpAxis estimated = {}) {
  return args.has("--up") ? parse_up_axis(args.str("--up")) : estimated;
}

/// Writes every requested output (each atomically; io::Error names the file on failure) and
/// adds its name to `written`. `title` names the map in pictures and pages; `note` goes into the
/// .bt/.ot headers (io::encode_bt).
inline void write_map_outputs(const OccupancyMap<OcKey>& map, const Args& args, UpAxis up,
                              const std::string& title, std::vector<std::string>& written,
                              const std::string& note = {}) {
  auto done = [&](const char* flag) { written.push_back(args.str(flag)); };
  if (args.has("--out-bt")) {
    io::write_bt(args.str("--out-bt"), map, note);
    done("--out-bt");
  }
  if (args.has("--out-ot")) {
    io::write_ot(args.str("--out-ot"), map, note);
    done("--out-ot");
  }
  if (args.has("--out-ply")) {
    io::VoxelExportOptions o;
    o.shape = args.flag("--ply-cubes") ? io::VoxelShape::cubes : io::VoxelShape::points;
    o.which = args.flag("--ply-free") ? io::VoxelSelection::all : io::VoxelSelection::occupied;
    io::write_voxels_ply(args.str("--out-ply"), map, o);
    done("--out-ply");
  }
  if (args.has("--out-png")) {
    write_map_png(args.str("--out-png"), map, up, title);
    done("--out-png");
  }
  if (args.has("--out-html")) {
    write_view_page(args.str("--out-html"), {ViewMap{title, &map}}, up, ViewOptions{});
    done("--out-html");
  }
}

}  // namespace knnocc::cli
