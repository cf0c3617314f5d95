#pragma once
// knnocc map --save-every N: snapshots that resume. Every N clouds the --out-bt and --out-ot maps
// are written together (an io::CommitGroup: both from the same cloud, renamed one after the
// other once both are complete), and each file says in its header which clouds it holds:
//   # knnocc map: clouds 0 to 14 of SEQ; continue with --first 15
// (a comment line, skipped by OctoMap's readers; `knnocc info` prints it). A killed run is resumed
// with `--init-map FILE.ot --first 15` (the .ot continues exactly; a .bt only occupied/free); the
// maps of a run that ends normally carry the same line. An --init-map whose line names the same
// input and another --first is refused: it would map clouds twice or leave some out.

#include <cstddef>
#include <filesystem>
#include <string>
#include <system_error>

#include <knnocc/insertion/voxel_colors.hpp>
#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/octomap_tree.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "args.hpp"

namespace knnocc::cli {

/// The clouds [first, end) of `input` a map holds, as its header note says.
struct HeldClouds {
  std::size_t first = 0, end = 0;
  std::string input;  // printable (as written)
};

inline std::string held_clouds_note(const HeldClouds& h) {
  return "map: clouds " + std::to_string(h.first) + " to " + std::to_string(h.end - 1) + " of " +
         io::printable(h.input) + "; continue with --first " + std::to_string(h.end);
}

/// Reads a note held_clouds_note() wrote; false for any other note.
inline bool parse_held_clouds(const std::string& note, HeldClouds& h) {
  const std::string head = "map: clouds ", of = " of ", tail = "; continue with --first ";
  const std::size_t t = note.rfind(tail);
  if (note.rfind(head, 0) != 0 || t == std::string::npos) return false;
  std::size_t last = 0;
  int used = 0;
  if (std::sscanf(note.c_str() + head.size(), "%zu to %zu of %n", &h.first, &last, &used) != 2 ||
      used == 0 || head.size() + static_cast<std::size_t>(used) > t)
    return false;
  h.input = note.substr(head.size() + static_cast<std::size_t>(used),
                        t - head.size() - static_cast<std::size_t>(used));
  h.end = last + 1;
  return note.substr(t + tail.size()) == std::to_string(h.end);
}

/// Whether two paths name the same place ("seq", "./seq", "seq/"): compared resolved.
inline bool same_path(const std::string& a, const std::string& b) {
  std::error_code ea, eb;
  const auto ca = std::filesystem::weakly_canonical(a, ea),
             cb = std::filesystem::weakly_canonical(b, eb);
  return ea || eb ? a == b : ca == cb;
}

/// The first cloud a run's maps hold: `first`, or an --init-map's first when that map holds
/// clouds of the same input up to `first`. UsageError when it holds clouds of this input but
/// does not end where --first starts.
inline std::size_t first_held_cloud(const std::string& init_map, const std::string& input,
                                    std::size_t first) {
  HeldClouds h;
  if (init_map.empty() || !parse_held_clouds(io::inspect_octree(init_map).note, h) ||
      !same_path(h.input, io::printable(input)))
    return first;
  if (h.end != first)
    throw UsageError("--init-map " + init_map + " holds clouds " + std::to_string(h.first) +
                     " to " + std::to_string(h.end - 1) + " of " + input +
                     ": continue with --first " + std::to_string(h.end) + ", not " +
                     std::to_string(first));
  return h.first;
}

/// One --save-every snapshot: the --out-bt and --out-ot files, committed together.
inline void save_snapshot(const Args& args, const OccupancyMap<OcKey>& map, const std::string& note,
                          const VoxelColors<OcKey>* colors = nullptr) {
  io::CommitGroup group;
  if (args.has("--out-bt")) io::write_bt(args.str("--out-bt"), map, note);
  if (args.has("--out-ot") && colors)
    io::write_color_ot(
        args.str("--out-ot"), map, [colors](const OcKey& k) { return colors->mean(k); }, note);
  else if (args.has("--out-ot"))
    io::write_ot(args.str("--out-ot"), map, note);
  group.commit();
}

}  // namespace knnocc::cli
