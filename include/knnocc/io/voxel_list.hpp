// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The plain voxel-list format used to compare maps across implementations: one voxel per line,
// "x y z logodds" printed as "%.6f %.6f %.6f %.6f", sorted by x, then y, then z, so two maps can
// be compared with diff or a line-by-line numeric tolerance check.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <tuple>
#include <vector>

#include "../map/occupancy_map.hpp"
#include "detail/file_text.hpp"
#include "error.hpp"

namespace knnocc::io {

struct VoxelRecord {
  double x, y, z;  // voxel centre
  float logodds;
};

/// Which voxels of a map an export takes (occupied: the map's occupancy threshold).
enum class VoxelSelection { occupied, free, all };

/// The map's finest-level voxels as records (centre, log-odds), in the map's storage order.
template <class Key>
std::vector<VoxelRecord> voxel_records(const OccupancyMap<Key>& map,
                                       VoxelSelection which = VoxelSelection::all) {
  std::vector<VoxelRecord> out;
  out.reserve(which == VoxelSelection::all ? map.num_voxels() : 0);
  const auto& g = map.grid();
  map.for_each_voxel([&](const Key& k, float v) {
    if (which != VoxelSelection::all && map.is_occupied(v) != (which == VoxelSelection::occupied))
      return;
    out.push_back({g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2]), v});
  });
  return out;
}

// Sorts `voxels` and writes them atomically (temp file + rename). Non-finite coordinates are an
// error (they have no place in the order); a non-finite logodds is written as nan/inf.
inline void write_voxel_list(const std::string& path, std::vector<VoxelRecord> voxels) {
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const VoxelRecord& v = voxels[i];
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
      throw Error(path, "voxel " + std::to_string(i) + " has a non-finite coordinate");
    }
  }
  std::sort(voxels.begin(), voxels.end(), [](const VoxelRecord& a, const VoxelRecord& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });

  AtomicFile out(path);
  // Formatted into a reused 1 MiB chunk: far cheaper than a stream, no 50 MB string either.
  std::vector<char> chunk(1 << 20);
  char* const lim = chunk.data() + chunk.size();
  char* w = chunk.data();
  for (const VoxelRecord& v : voxels) {
    if (lim - w < 4 * 360) {  // room for four worst-case "%.6f" fields
      out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
      w = chunk.data();
    }
    w = detail::format_fixed6(w, lim, v.x);
    *w++ = ' ';
    w = detail::format_fixed6(w, lim, v.y);
    *w++ = ' ';
    w = detail::format_fixed6(w, lim, v.z);
    *w++ = ' ';
    w = detail::format_fixed6(w, lim, static_cast<double>(v.logodds));
    *w++ = '\n';
  }
  out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
  out.commit();
}

// Reads a voxel list back (blank lines and '#' comments skipped). Exactly 4 numbers per line.
inline std::vector<VoxelRecord> read_voxel_list(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  std::vector<VoxelRecord> voxels;
  voxels.reserve(buf.size() / 40 + 1);
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    double v[5];
    const std::size_t n = detail::scan_line_numbers(path, line, b, e, v, 5, true);
    if (n == 0) return;
    if (n != 4) {
      throw Error(path, "line " + std::to_string(line) +
                            ": expected 4 numbers (x y z logodds), found " +
                            (n > 4 ? std::string("more") : std::to_string(n)));
    }
    voxels.push_back(VoxelRecord{v[0], v[1], v[2], detail::to_float(v[3])});
  });
  return voxels;
}

}  // namespace knnocc::io
