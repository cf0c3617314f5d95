#pragma once
// knnocc view MAP... --out page.html: maps in 3D in one self-contained web page.

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/io/octomap_tree.hpp>

#include "args.hpp"
#include "convert_command.hpp"
#include "input_guard.hpp"
#include "resource_limits.hpp"
#include "view_page.hpp"

namespace knnocc::cli {

/// The most maps one page shows (each has its button and its data in the page).
inline constexpr std::size_t kMaxViewMaps = 64;

inline const char* view_help() {
  return R"(usage: knnocc view MAP... --out PAGE.html [options]

Writes one web page (three.js embedded: it opens without a network) that shows the maps in 3D:
occupied voxels as cubes coloured by height (the same colours and up axis as the pictures),
free voxels on a toggle, buttons to switch between the maps (e.g. OctoMap model and k-NN model).
Drag to turn, shift or right drag to move, the wheel to zoom, r to reset the view.
Only the faces between an occupied and a non-occupied cell are drawn; a map with more exposed
faces than --max-faces is drawn at a coarser level (cells of 2, 4, ... voxels, occupied when
any voxel in them is), and the page says so.
  MAP                   .bt or .ot (OctoMap trees), or a voxel list (x y z logodds per line, as
                        --out-voxels writes) named .voxels or .txt, which needs --res; up to 64
  -o, --out FILE        the page to write (required)
  --names A,B,...       the maps' names on the page (default: the file names)
  --up AXIS             up: x, y, z, -x, -y or -z (default z: map files hold no poses)
  -r, --res R           voxel edge of voxel-list inputs
  --max-faces N         exposed faces drawn per map before coarsening (default 2500000)
Prints `wrote FILE (N maps)`. Exit status 2 on bad input (one line naming the file).
)";
}

inline int run_view(const std::vector<std::string>& argv) {
  const Args args(argv, {"--out", "--names", "--up", "--res", "--max-faces"}, {}, argv.size());
  if (args.help()) {
    std::fputs(view_help(), stdout);
    return 0;
  }
  if (args.positional().empty()) throw UsageError("needs at least one MAP (see --help)");
  if (args.positional().size() > kMaxViewMaps)
    throw UsageError("at most " + std::to_string(kMaxViewMaps) + " maps fit one page, got " +
                     std::to_string(args.positional().size()));
  const std::string out = args.required("--out");
  OutputList inputs;
  for (const std::string& in : args.positional()) inputs.emplace_back("MAP", in);
  check_outputs({{"--out", out}});
  check_outputs_not_inputs({{"--out", out}}, inputs);
  const UpAxis up = args.has("--up") ? parse_up_axis(args.str("--up")) : UpAxis{};
  ViewOptions opt;
  const long faces = args.integer("--max-faces", static_cast<long>(opt.max_faces));
  if (faces < 1000)
    throw UsageError("--max-faces must be at least 1000, got " + args.str("--max-faces"));
  opt.max_faces = static_cast<std::size_t>(faces);
  std::vector<std::string> names;
  if (args.has("--names")) {
    std::string s = args.str("--names"), cur;
    for (const char c : s + ",") {
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
  }
  if (!view_pages_available())
    throw io::Error(out,
                    "this knnocc was built without three.js (install libjs-three and "
                    "configure again)");
  std::vector<OccupancyMap<OcKey>> maps;
  maps.reserve(args.positional().size());
  for (const std::string& in : args.positional()) {
    const std::string ext = lower_extension(in);
    if (ext == ".bt" || ext == ".ot") {
      maps.push_back(read_tree_checked(in));
    } else if (ext == ".voxels" || ext == ".txt") {
      if (!args.has("--res")) throw UsageError("the voxel list " + in + " needs --res");
      const double res = args.number("--res", 0.0);
      if (!(res > 0.0)) throw UsageError("--res must be > 0, got " + args.str("--res"));
      maps.push_back(detail::read_voxel_list_map(in, res));
    } else {
      throw UsageError("unknown map extension '" + ext + "' of " + in +
                       " (.bt .ot, or a voxel list .voxels/.txt)");
    }
  }
  std::vector<ViewMap> views;
  for (std::size_t i = 0; i < maps.size(); ++i)
    views.push_back(
        {names.empty() ? std::filesystem::path(args.positional()[i]).filename().string() : names[i],
         &maps[i]});
  write_view_page(out, views, up, opt);
  std::printf("wrote %s (%zu map%s)\n", out.c_str(), maps.size(), maps.size() == 1 ? "" : "s");
  return 0;
}

}  // namespace knnocc::cli
