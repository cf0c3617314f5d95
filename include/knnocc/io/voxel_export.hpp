// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Map voxels as PLY for CloudCompare, MeshLab and friends: one point per voxel centre, or one
// cube (8 corners, 6 quad faces) per voxel. Binary little-endian (or ascii), atomic.
//
// Vertices carry "uchar red green blue" (occupied voxels coloured by height over the exported
// range, or by their own colour when a colour lookup gives one; free voxels light grey) and, for
// points, "float logodds" (a scalar field in CloudCompare). Voxels are written sorted by key (x,
// then y, then z), so the same map always gives the same file.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "../core/rgb.hpp"
#include "../map/occupancy_map.hpp"
#include "atomic_file.hpp"
#include "detail/bytes.hpp"
#include "detail/colormap.hpp"
#include "detail/file_text.hpp"
#include "error.hpp"
#include "voxel_list.hpp"

namespace knnocc::io {

enum class VoxelShape { points, cubes };

struct VoxelExportOptions {
  VoxelSelection which = VoxelSelection::occupied;
  VoxelShape shape = VoxelShape::points;
  bool binary = true;
};

namespace detail {

struct ExportedVoxel {
  std::uint64_t key;  // packed, for the order
  double c[3];        // centre
  float logodds;
  bool occupied;
};

template <class Key>
std::vector<ExportedVoxel> select_voxels(const OccupancyMap<Key>& map, VoxelSelection which) {
  std::vector<ExportedVoxel> v;
  const auto& g = map.grid();
  map.for_each_voxel([&](const Key& k, float l) {
    const bool occ = map.is_occupied(l);
    if (which != VoxelSelection::all && occ != (which == VoxelSelection::occupied)) return;
    v.push_back({k.pack(),
                 {g.index_to_coord(k[0]), g.index_to_coord(k[1]), g.index_to_coord(k[2])},
                 l,
                 occ});
  });
  std::sort(v.begin(), v.end(),
            [](const ExportedVoxel& a, const ExportedVoxel& b) { return a.key < b.key; });
  return v;
}

class PlyBody {  // binary or ascii records of float / uchar / int values
 public:
  explicit PlyBody(bool binary) : binary_(binary) {}
  void f(float v) {
    if (binary_) {
      char b[4];
      store_le(b, v);
      out_.append(b, 4);
    } else {
      sep();
      char buf[64];
      out_.append(buf, format_float_roundtrip(buf, buf + sizeof buf, v));
    }
  }
  void u8(std::uint8_t v) {
    if (binary_) {
      out_ += static_cast<char>(v);
    } else {
      sep();
      out_ += std::to_string(v);
    }
  }
  void i32(std::int32_t v) {
    if (binary_) {
      char b[4];
      store_le(b, v);
      out_.append(b, 4);
    } else {
      sep();
      out_ += std::to_string(v);
    }
  }
  void end_record() {
    if (!binary_) out_ += '\n';
    first_ = true;
  }
  std::string& str() { return out_; }

 private:
  void sep() {
    if (!first_) out_ += ' ';
    first_ = false;
  }
  bool binary_;
  bool first_ = true;
  std::string out_;
};

}  // namespace detail

/// Writes the selected voxels of `map` as PLY points or cubes; occupied voxels for which
/// `color_of` gives a colour get it. Returns the number of voxels.
template <class Key>
std::size_t write_voxels_ply(const std::string& path, const OccupancyMap<Key>& map,
                             const VoxelExportOptions& options = {},
                             const VoxelColorOf<Key>& color_of = {}) {
  const std::vector<detail::ExportedVoxel> voxels = detail::select_voxels(map, options.which);
  const bool cubes = options.shape == VoxelShape::cubes;
  if (cubes &&
      voxels.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max() / 8)) {
    throw Error(path, "too many voxels for a PLY mesh with int vertex indices");
  }
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  for (const auto& v : voxels) {
    if (!v.occupied) continue;
    zmin = std::min(zmin, v.c[2]);
    zmax = std::max(zmax, v.c[2]);
  }
  const double zspan = zmax > zmin ? zmax - zmin : 1.0;
  auto colour = [&](const detail::ExportedVoxel& v) {
    if (!v.occupied) return std::array<std::uint8_t, 3>{200, 200, 200};
    if (color_of)
      if (const std::optional<Rgb> c = color_of(Key::unpack(v.key)))
        return std::array<std::uint8_t, 3>{c->r, c->g, c->b};
    return detail::height_colour((v.c[2] - zmin) / zspan);
  };

  const std::size_t vertices = cubes ? 8 * voxels.size() : voxels.size();
  std::string header = "ply\nformat ";
  header += options.binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  header += "comment knnocc voxels, resolution " + std::to_string(map.resolution()) + " m\n";
  header += "element vertex " + std::to_string(vertices) +
            "\nproperty float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (!cubes) header += "property float logodds\n";
  if (cubes) {
    header += "element face " + std::to_string(6 * voxels.size()) +
              "\nproperty list uchar int vertex_indices\n";
  }
  header += "end_header\n";

  detail::PlyBody body(options.binary);
  body.str().reserve(vertices * (cubes ? 15 : 19) + (cubes ? voxels.size() * 6 * 17 : 0));
  const double h = map.resolution() / 2;
  for (const auto& v : voxels) {
    const auto rgb = colour(v);
    const int corners = cubes ? 8 : 1;
    for (int c = 0; c < corners; ++c) {
      for (int a = 0; a < 3; ++a) {
        const double off = cubes ? (((c >> a) & 1) ? h : -h) : 0.0;
        body.f(static_cast<float>(v.c[a] + off));
      }
      body.u8(rgb[0]);
      body.u8(rgb[1]);
      body.u8(rgb[2]);
      if (!cubes) body.f(v.logodds);
      body.end_record();
    }
  }
  if (cubes) {
    // Corner c has bit 0 = +x, bit 1 = +y, bit 2 = +z; faces wound counter-clockwise seen from
    // outside.
    static const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (std::size_t i = 0; i < voxels.size(); ++i) {
      const auto base = static_cast<std::int32_t>(8 * i);
      for (const auto& f : faces) {
        body.u8(4);
        for (int k = 0; k < 4; ++k) body.i32(base + f[k]);
        body.end_record();
      }
    }
  }
  AtomicFile out(path);
  out.write(header);
  out.write(body.str());
  out.commit();
  return voxels.size();
}

}  // namespace knnocc::io
