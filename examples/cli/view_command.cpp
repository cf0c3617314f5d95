// knnocc view MAP... [--out page.html] [--path SEQ]: maps in 3D in one self-contained web page.

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "common_options.hpp"
#include "input_guard.hpp"
#include "map_colors.hpp"
#include "map_files.hpp"
#include "output_set.hpp"
#include "tile_set_files.hpp"
#include "view_page.hpp"

namespace knnocc::cli {

namespace {

constexpr std::size_t kMaxViewMaps = 64;

CommandSpec make_view_spec() {
  CommandSpec s;
  s.name = "view";
  s.summary = "maps in 3D: one self-contained web page (three.js embedded)";
  s.usage = "knnocc view MAP... [--out PAGE.html] [--path SEQ] [options]";
  s.text =
      R"(Writes one web page (three.js embedded: it opens without a network) that shows the maps in 3D:
occupied voxels as cubes coloured by height (the same colours and up axis as the pictures),
free voxels on a toggle, buttons to switch between the maps (e.g. OctoMap model and k-NN model).
Drag to turn, shift or right drag to move, the wheel to zoom, r to reset the view.
Only the faces between an occupied and a non-occupied cell are drawn; a map with more exposed
faces than --max-faces is drawn at a coarser level (cells of 2, 4, ... voxels, occupied when
any voxel in them is), and the page says so.
  MAP                   .bt or .ot (OctoMap trees), or a voxel list (x y z logodds per line, as
                        --out-voxels writes) named .voxels or .txt, which needs --res; at most 64;
                        or a tile set folder (knnocc map --out-tiles), read tile by tile: its
                        free voxels too when they fit --memory-limit, and a map beyond
                        OctoMap's key range at the finest coarser resolution that holds it
The page is the first MAP's name with .html unless --out names it. --path draws the camera path
of the sequence the map was built from. Prints `wrote FILE (N maps)`.
)";
  s.groups.push_back(
      {"options",
       {Option::text("--out", "FILE", "the page to write")
            .alias("-o")
            .fallback_text("the first MAP with .html"),
        Option::text("--path", "SEQ",
                     "draw a camera path: a sequence folder's poses (up is then estimated from "
                     "them, as knnocc map does) or a trajectory file (poses.txt format)"),
        Option::text("--names", "A,B,...", "the maps' names on the page")
            .fallback_text("the file names"),
        up_option("from --path's poses, else z (map files hold no poses)"),
        Option::number("--res", "R", "voxel edge of voxel-list inputs")
            .alias("-r")
            .at_least(kMinResolution),
        Option::integer("--max-faces", "N", "exposed faces drawn per map before coarsening")
            .fallback(std::to_string(ViewOptions{}.max_faces))
            .at_least(1000),
        memory_limit_option()},
       ""});
  s.footer = "Exit status 2 on bad input (one line naming the file).\n";
  s.max_positional = kMaxViewMaps;
  s.positional_limit_why = "maps fit one page";
  return s;
}

/// --names split at commas, one per map (empty: the file names).
std::vector<std::string> view_names(const Args& args) {
  std::vector<std::string> names;
  if (!args.has("--names")) return names;
  std::string cur;
  for (const char c : args.str("--names") + ",") {
    if (c == ',') {
      names.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (names.size() != args.positional().size())
    throw UsageError("--names has " + std::to_string(names.size()) + " names for " +
                     std::to_string(args.positional().size()) + " maps");
  return names;
}

/// A map to show, with a ColorOcTree's colours into `colors`.
OccupancyMap<OcKey> read_view_map(const Args& args, const std::string& in,
                                  io::OctreeColors& colors) {
  if (is_tile_set_path(in)) return read_tile_set_map(in, true, "view");
  const std::string ext = lower_extension(in);
  if (!is_tree_file(in) && ext != ".voxels" && ext != ".txt")
    throw UsageError("unknown map extension '" + ext + "' of " + in +
                     " (.bt .ot, or a voxel list .voxels/.txt)");
  if (!is_tree_file(in) && !args.has("--res"))
    throw UsageError("the voxel list " + in + " needs --res");
  return read_map_file(in, is_tree_file(in) ? 0.0 : args.number("--res"), &colors);
}

/// The camera positions of --path and the up they suggest (a folder's first cloud tells a camera
/// from a LiDAR; a trajectory file alone suggests nothing).
std::vector<Point3d> view_path(const std::string& path, std::optional<UpAxis>& up) {
  std::vector<io::Pose> poses;
  if (io::is_sequence_dir(path)) {
    const io::Sequence seq = io::Sequence::open(path);
    poses = seq.poses();
    if (!poses.empty()) {
      const std::vector<Point3f> first = seq.load_cloud(0).points;
      UpEstimator estimate;
      for (const io::Pose& p : poses) estimate.add(p, first);
      up = estimate.result();
    }
  } else {
    poses = io::read_trajectory(path);
  }
  std::vector<Point3d> out;
  for (const io::Pose& p : poses) out.push_back(Point3d{p.t.x(), p.t.y(), p.t.z()});
  return out;
}

}  // namespace

const CommandSpec& view_spec() {
  static const CommandSpec spec = make_view_spec();
  return spec;
}

int run_view(const Args& args) {
  if (args.positional().empty()) throw UsageError("needs at least one MAP (see --help)");
  const std::string out = args.str(
      "--out", std::filesystem::path(args.positional()[0]).replace_extension(".html").string());
  OutputList inputs;
  for (const std::string& in : args.positional()) inputs.emplace_back("MAP", in);
  if (args.has("--path")) inputs.emplace_back("--path", args.str("--path"));
  check_outputs({{"--out", out}});
  check_outputs_not_inputs({{"--out", out}}, inputs);
  ViewOptions opt;
  std::optional<UpAxis> path_up;
  if (args.has("--path")) opt.path = view_path(args.str("--path"), path_up);
  const UpAxis up = up_axis(args, path_up.value_or(UpAxis{}));
  opt.max_faces = static_cast<std::size_t>(args.integer("--max-faces"));
  const std::vector<std::string> names = view_names(args);
  if (!view_pages_available())
    throw io::Error(out,
                    "this knnocc was built without three.js (install libjs-three and "
                    "configure again)");
  use_memory_limit(args);
  std::vector<OccupancyMap<OcKey>> maps;
  std::vector<VoxelColors<OcKey>> colors;  // a ColorOcTree's colours go to the page
  maps.reserve(args.positional().size());
  colors.reserve(args.positional().size());
  for (const std::string& in : args.positional()) {
    io::OctreeColors tree;
    maps.push_back(read_view_map(args, in, tree));
    colors.emplace_back(maps.back().resolution());
    reading(in, [&] { add_tree_colors(colors.back(), tree); });
    note_free_colors("view", in, tree);
  }
  std::vector<ViewMap> views;
  for (std::size_t i = 0; i < maps.size(); ++i)
    views.push_back(
        {names.empty() ? std::filesystem::path(args.positional()[i]).filename().string() : names[i],
         &maps[i], colors[i].empty() ? nullptr : &colors[i]});
  write_view_page(out, views, up, opt);
  std::printf("wrote %s (%zu map%s)\n", io::printable(out).c_str(), maps.size(),
              maps.size() == 1 ? "" : "s");
  return 0;
}

}  // namespace knnocc::cli
