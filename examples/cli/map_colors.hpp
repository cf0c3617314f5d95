#pragma once
// Colour along the tool's paths: a ColorOcTree's colours read back as voxel colours (`convert`,
// `map --init-map`), and the one note on stderr when a file being written cannot keep colours
// the map or cloud has (a .bt, a voxel list, an .xyz ...): colours are never dropped silently.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/insertion/voxel_colors.hpp>
#include <knnocc/io/octomap_tree.hpp>

#include "map_outputs.hpp"

namespace knnocc::cli {

/// A read ColorOcTree's colours into `out`: each coloured voxel counts as one point of its
/// colour (so after --init-map a voxel's colour is the mean of that and the new points').
inline void add_tree_colors(VoxelColors<OcKey>& out, const io::OctreeColors& tree) {
  for (const auto& [key, rgb] : tree.voxels) out.add(key, rgb);
}

/// Whether a map file of this format keeps the voxels' colours (.ot as a ColorOcTree, .ply,
/// .html); .bt, voxel lists, pictures and 2D grids have no place for them.
inline bool keeps_colors(MapFormat f) {
  return f == MapFormat::ot || f == MapFormat::ply || f == MapFormat::html;
}

/// Prints, once, "knnocc COMMAND: SOURCE: note: the WHAT's colours are not kept by FILES (WHY)"
/// when `files` is not empty.
inline void note_colors_not_kept(const char* command, const std::string& source, const char* what,
                                 const std::vector<std::string>& files, const std::string& why) {
  if (files.empty()) return;
  std::string list;
  for (const std::string& f : files) list += (list.empty() ? "" : ", ") + io::printable(f);
  std::fprintf(stderr, "knnocc %s: %s: note: the %s's colours are not kept by %s (%s)\n", command,
               io::printable(source).c_str(), what, list.c_str(), why.c_str());
}

/// A ColorOcTree's colours of free voxels, which knnocc does not keep (it colours occupied
/// voxels only): one note when there are any.
inline void note_free_colors(const char* command, const std::string& path,
                             const io::OctreeColors& tree) {
  if (tree.free_colored_voxels == 0) return;
  std::fprintf(stderr,
               "knnocc %s: %s: note: the colours of its %llu free voxels are not kept (knnocc "
               "colours occupied voxels only)\n",
               command, io::printable(path).c_str(),
               static_cast<unsigned long long>(tree.free_colored_voxels));
}

}  // namespace knnocc::cli
