#pragma once
// The map files `knnocc map` (and `knnocc convert`) can write: OctoMap trees for
// octovis/octomap_server (a ColorOcTree .ot when the map has colours), PLY voxels for
// CloudCompare/MeshLab, a PNG picture, a 3D web page, a ROS map_server / Nav2 2D grid and voxel
// lists. Each --out-FORMAT option names one; -o FILE names any, by its extension.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <knnocc/insertion/voxel_colors.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/ros_map.hpp>
#include <knnocc/io/voxel_export.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/map/occupancy_grid_2d.hpp>
#include <knnocc/map/occupancy_map.hpp>
#include <knnocc/sensor/knn2022_model.hpp>
#include <knnocc/sensor/knn_model.hpp>
#include <knnocc/sensor/octomap_model.hpp>
#include <knnocc/sensor/robust_model.hpp>

#include "args.hpp"
#include "map_picture.hpp"
#include "output_set.hpp"
#include "resource_limits.hpp"
#include "view_page.hpp"

namespace knnocc::cli {

inline std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

/// A map file's format.
enum class MapFormat { bt, ot, ply, png, html, grid, voxels };

/// The format of `path` by its extension, or nullopt.
inline std::optional<MapFormat> map_format(const std::string& path) {
  const std::string e = lower_extension(path);
  if (e == ".bt") return MapFormat::bt;
  if (e == ".ot") return MapFormat::ot;
  if (e == ".ply") return MapFormat::ply;
  if (e == ".png") return MapFormat::png;
  if (e == ".html" || e == ".htm") return MapFormat::html;
  if (e == ".yaml" || e == ".yml") return MapFormat::grid;
  if (e == ".voxels" || e == ".txt") return MapFormat::voxels;
  return std::nullopt;
}

/// A map file to write: the option that asked for it, its path and format.
struct MapFile {
  std::string option, path;
  MapFormat format;
};

/// The map files given by `options` (each --out-FORMAT needs its format's extension, like
/// octovis picks its reader by it) and by every -o; UsageError for a wrong or unknown extension.
inline std::vector<MapFile> requested_map_files(const Args& args,
                                                const std::vector<std::string>& options) {
  struct Fixed {
    const char* option;
    MapFormat format;
    const char* extension;  // "": any name (e.g. a device)
  };
  static const Fixed kFixed[] = {
      {"--out-bt", MapFormat::bt, ".bt"},     {"--out-ot", MapFormat::ot, ".ot"},
      {"--out-ply", MapFormat::ply, ""},      {"--out-png", MapFormat::png, ".png"},
      {"--out-html", MapFormat::html, ""},    {"--out-grid", MapFormat::grid, ".yaml"},
      {"--out-voxels", MapFormat::voxels, ""}};
  std::vector<MapFile> files;
  for (const Fixed& o : kFixed) {
    if (std::find(options.begin(), options.end(), o.option) == options.end() || !args.has(o.option))
      continue;
    const std::string path = args.str(o.option);
    if (*o.extension && map_format(path) != o.format)
      throw UsageError(std::string(o.option) + " needs a file name ending in " + o.extension +
                       ", got '" + path + "'");
    files.push_back({o.option, path, o.format});
  }
  for (const std::string& path : args.all("--output")) {
    const std::optional<MapFormat> format = map_format(path);
    if (!format)
      throw UsageError("-o " + path +
                       ": the extension names no map format (.bt .ot .ply .png .html .yaml "
                       ".voxels .txt)");
    files.push_back({"-o", path, *format});
  }
  return files;
}

/// The outputs to check before any work: every map file, and the image of a 2D grid (io::Error
/// when its name cannot be written in the YAML).
inline OutputList map_file_outputs(const std::vector<MapFile>& files) {
  OutputList out;
  for (const MapFile& f : files) {
    out.emplace_back(f.option, f.path);
    if (f.format != MapFormat::grid) continue;
    (void)io::ros_map_image_entry(f.path);  // a name the YAML cannot hold: refused before work
    out.emplace_back(f.option, io::ros_map_image_path(f.path));
  }
  return out;
}

/// The flags that only some map files take, checked against the files asked for.
inline void check_map_file_flags(const Args& args, const std::vector<MapFile>& files) {
  const auto any = [&](MapFormat f) {
    return std::any_of(files.begin(), files.end(), [f](const MapFile& m) { return m.format == f; });
  };
  if ((args.flag("--ply-cubes") || args.flag("--ply-free")) && !any(MapFormat::ply))
    throw UsageError("--ply-cubes and --ply-free need a .ply output (--out-ply or -o FILE.ply)");
  if (any(MapFormat::grid) && !args.has("--grid-z"))
    throw UsageError(
        "a 2D grid (.yaml) needs --grid-z MIN:MAX, the height band along up that it shows "
        "(metres, e.g. 0.1:1.5 for a robot 1.5 m tall)");
  if (args.has("--grid-z") && !any(MapFormat::grid))
    throw UsageError("--grid-z needs a 2D grid output (--out-grid or -o FILE.yaml)");
}

/// --ply-cubes / --ply-free as export options.
inline io::VoxelExportOptions ply_export_options(const Args& args) {
  io::VoxelExportOptions o;
  o.shape = args.flag("--ply-cubes") ? io::VoxelShape::cubes : io::VoxelShape::points;
  o.which = args.flag("--ply-free") ? io::VoxelSelection::all : io::VoxelSelection::occupied;
  return o;
}

/// --voxels / --out-voxels' selection by name: occupied, free or all.
inline io::VoxelSelection voxel_selection(const std::string& which) {
  return which == "occupied" ? io::VoxelSelection::occupied
         : which == "free"   ? io::VoxelSelection::free
                             : io::VoxelSelection::all;
}

/// "MIN:MAX" (--grid-z, --clamp) as two numbers with MIN < MAX; UsageError naming `flag`.
inline std::pair<double, double> parse_range(const std::string& flag, const std::string& text) {
  const std::size_t colon = text.find(':');
  char* end = nullptr;
  double v[2] = {0, 0};
  bool ok = colon != std::string::npos;
  for (int i = 0; ok && i < 2; ++i) {
    const std::string part = i ? text.substr(colon + 1) : text.substr(0, colon);
    v[i] = std::strtod(part.c_str(), &end);
    ok = !part.empty() && *end == '\0' && std::isfinite(v[i]);
  }
  if (!ok || !(v[0] < v[1]))
    throw UsageError(flag + " needs MIN:MAX with MIN < MAX (e.g. 0.1:1.5), got '" + text + "'");
  return {v[0], v[1]};
}

/// The model's name as --model takes it.
inline const char* model_name(const OctoMapModel&) { return "octomap"; }
inline const char* model_name(const KnnModel&) { return "knn"; }
inline const char* model_name(const RobustModel&) { return "robust"; }
inline const char* model_name(const Knn2022Model&) { return "knn2022"; }

/// The model's name in titles and pictures.
inline const char* model_title(const OctoMapModel&) { return "OctoMap model"; }
inline const char* model_title(const KnnModel&) { return "k-NN model"; }
inline const char* model_title(const RobustModel&) { return "robust model"; }
inline const char* model_title(const Knn2022Model&) { return "2022 k-NN model"; }

/// The notes (stderr) on points a map holds no update from: NaN/Inf coordinates, points outside
/// the key range (|c| >= max_coord), e.g. moved there by a correction.
inline void note_skipped_points(const std::string& input, std::size_t nonfinite,
                                std::size_t out_of_range, double max_coord, double res) {
  if (nonfinite)
    std::fprintf(stderr, "knnocc map: %s: skipped %zu points with NaN/Inf coordinates\n",
                 input.c_str(), nonfinite);
  if (out_of_range)
    std::fprintf(stderr,
                 "knnocc map: %s: skipped %zu points outside the map's key range (|c| >= %g m at "
                 "--res %g); use a coarser --res%s\n",
                 input.c_str(), out_of_range, max_coord, res,
                 max_coord <= 32768.0 * res * 1.5 ? ", or --key-bits 21 (64x farther)" : "");
}

/// A warning (stderr) when clouds were read and the map holds no voxel: never silent.
template <class Model>
void note_empty_map(const std::string& input, std::size_t clouds, std::size_t points,
                    std::size_t known_voxels, const Model&) {
  if (clouds == 0 || known_voxels > 0) return;
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
  for (std::size_t i = 0; i < written.size(); ++i)
    line += (i ? ", " : " ") + io::printable(written[i]);
  std::printf("%s\n", line.c_str());
}

/// --up if given, else `estimated`.
inline UpAxis up_axis(const Args& args, UpAxis estimated = {}) {
  return args.has("--up") ? parse_up_axis(args.str("--up")) : estimated;
}

/// What map files show besides the map itself.
struct MapFileContext {
  UpAxis up;
  std::string title;                                    ///< names the map in pictures and pages
  const VoxelColors<OcKey>* colors = nullptr;           ///< the occupied voxels' colours, if any
  std::vector<Point3d> path;                            ///< sensor positions, drawn in pages
  io::VoxelSelection voxels = io::VoxelSelection::all;  ///< what voxel lists hold
  std::optional<std::pair<double, double>> band;        ///< --grid-z, for 2D grids
  io::VoxelExportOptions ply;
  std::string note;  ///< goes into .bt/.ot headers (map_snapshots.hpp)
};

/// The 2D grid of the context's height band, written as NAME.yaml + NAME.pgm; returns its
/// summary line. io::Error naming the file when no known voxel lies in the band.
inline std::string write_grid_file(const OccupancyMap<OcKey>& map, const std::string& path,
                                   const MapFileContext& c) {
  const double lo = c.band->first, hi = c.band->second;  // captured below (not a binding)
  OccupancyGrid2D g;
  try {
    g = within_memory(path, "making the 2D grid", [&] {
      return project_height_band(map, PlaneFrame::with_up(c.up.axis, c.up.sign), lo, hi);
    });
  } catch (const std::invalid_argument& e) {  // more cells than a grid may have
    throw io::Error(path, std::string(e.what()) + "; a coarser --res makes fewer");
  }
  if (g.empty()) {
    double min = std::numeric_limits<double>::infinity(), max = -min;
    map.for_each_voxel([&](const OcKey& k, float) {
      const double h = c.up.sign * map.grid().index_to_coord(k[c.up.axis]);
      min = std::min(min, h), max = std::max(max, h);
    });
    char text[256];
    std::snprintf(text, sizeof text,
                  "no known voxel lies in --grid-z %g:%g along up %s; the map's voxels span "
                  "heights %.2f to %.2f m",
                  lo, hi, c.up.name().c_str(), min, max);
    throw io::Error(path, text);
  }
  within_memory(path, "writing the 2D grid", [&] { io::write_ros_map(path, g); });
  std::size_t n[3] = {0, 0, 0};  // occupied, free, unknown
  for (const std::int8_t cell : g.cells)
    ++n[cell == OccupancyGrid2D::kOccupied ? 0 : cell == OccupancyGrid2D::kFree ? 1 : 2];
  char line[256];
  std::snprintf(line, sizeof line,
                "grid %s: %zu x %zu cells of %g m, up %s, heights %g:%g m: occupied %zu free %zu "
                "unknown %zu",
                io::printable(path).c_str(), g.width, g.height, g.resolution, c.up.name().c_str(),
                lo, hi, n[0], n[1], n[2]);
  return line;
}

/// Writes one map file (atomically; io::Error names the file on failure); returns a line to
/// print for files that have one (2D grids), else "".
inline std::string write_map_file(const OccupancyMap<OcKey>& map, const MapFile& f,
                                  const MapFileContext& c) {
  const auto color_of = [&c](const OcKey& k) { return c.colors->mean(k); };
  switch (f.format) {
    case MapFormat::bt:
      io::write_bt(f.path, map, c.note);
      break;
    case MapFormat::ot:
      if (c.colors)
        io::write_color_ot(f.path, map, color_of, c.note);
      else
        io::write_ot(f.path, map, c.note);
      break;
    case MapFormat::ply:
      io::write_voxels_ply(f.path, map, c.ply,
                           c.colors ? VoxelColorOf<OcKey>(color_of) : VoxelColorOf<OcKey>());
      break;
    case MapFormat::png:
      write_map_png(f.path, map, c.up, c.title);
      break;
    case MapFormat::html: {
      ViewOptions opt;
      opt.path = c.path;
      write_view_page(f.path, {ViewMap{c.title, &map, c.colors}}, c.up, opt);
      break;
    }
    case MapFormat::grid:
      return write_grid_file(map, f.path, c);
    case MapFormat::voxels:
      io::write_voxel_list(f.path, io::voxel_records(map, c.voxels));
      break;
  }
  return "";
}

/// Writes every file of `files` (as one set: a failure leaves every target as it was); adds
/// their names to `written` and the lines to print to `notes`.
inline void write_map_files(const OccupancyMap<OcKey>& map, const std::vector<MapFile>& files,
                            const MapFileContext& c, std::vector<std::string>& written,
                            std::vector<std::string>& notes) {
  io::CommitGroup group;
  for (const MapFile& f : files) {
    const std::string note = write_map_file(map, f, c);
    if (!note.empty()) notes.push_back(note);
    written.push_back(f.path);
  }
  group.commit();
}

}  // namespace knnocc::cli
