#pragma once
// A picture of a map for --out-png: the top view (x right, y up, each column coloured by the
// height of its highest occupied voxel, known-free columns light grey) above the side view
// (x right, z up, coloured by height and darker with distance from the viewer at -y).

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <knnocc/io/detail/colormap.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/png.hpp>
#include <knnocc/map/occupancy_map.hpp>

namespace knnocc::cli {

struct Picture {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
  std::int64_t voxels_per_pixel = 1;
};

/// Renders `map` with at most `max_side` pixels of map per image side (large maps are drawn
/// with several voxels per pixel, small ones zoomed up to 8 pixels per voxel).
template <class Key>
Picture render_map_picture(const OccupancyMap<Key>& map, std::int64_t max_side = 1600) {
  constexpr std::int64_t kMargin = 8;
  std::int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<std::int64_t>::max();
    hi[a] = std::numeric_limits<std::int64_t>::min();
  }
  map.for_each_voxel([&](const Key& k, float) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min<std::int64_t>(lo[a], k[a]);
      hi[a] = std::max<std::int64_t>(hi[a], k[a]);
    }
  });
  Picture pic;
  if (map.empty()) return pic;
  const std::int64_t span[3] = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
  const std::int64_t longest = std::max(span[0], span[1] + span[2]);
  const std::int64_t s = (longest + max_side - 1) / max_side;  // voxels per pixel
  const std::int64_t w = (span[0] + s - 1) / s, ht = (span[1] + s - 1) / s,
                     hs = (span[2] + s - 1) / s;
  pic.voxels_per_pixel = s;
  pic.width = static_cast<std::uint32_t>(w + 2 * kMargin);
  pic.height = static_cast<std::uint32_t>(ht + hs + 3 * kMargin);

  // Per pixel: highest occupied z (top view) / nearest occupied y (side view), -1 = none;
  // free flags for known-free space.
  std::vector<std::int32_t> top(static_cast<std::size_t>(w * ht), -1),
      side(static_cast<std::size_t>(w * hs), -1);
  std::vector<std::uint8_t> top_free(top.size(), 0), side_free(side.size(), 0);
  map.for_each_voxel([&](const Key& k, float v) {
    const std::int64_t px = (k[0] - lo[0]) / s;
    const std::size_t t = static_cast<std::size_t>((hi[1] - k[1]) / s * w + px);
    const std::size_t d = static_cast<std::size_t>((hi[2] - k[2]) / s * w + px);
    if (!map.is_occupied(v)) {
      top_free[t] = side_free[d] = 1;
      return;
    }
    const auto z = static_cast<std::int32_t>(k[2] - lo[2]);
    const auto y = static_cast<std::int32_t>(k[1] - lo[1]);
    top[t] = std::max(top[t], z);
    if (side[d] < 0 || y < side[d]) side[d] = y;
  });

  pic.rgb.assign(std::size_t{pic.width} * pic.height * 3, 255);
  auto paint = [&](std::int64_t x, std::int64_t y, const std::array<std::uint8_t, 3>& c) {
    std::uint8_t* p = &pic.rgb[static_cast<std::size_t>((y * pic.width + x) * 3)];
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
  };
  const std::array<std::uint8_t, 3> free_colour{225, 228, 232}, frame{150, 150, 150};
  const double zr = static_cast<double>(std::max<std::int64_t>(span[2] - 1, 1));
  const double yr = static_cast<double>(std::max<std::int64_t>(span[1] - 1, 1));
  for (std::int64_t r = 0; r < ht; ++r) {
    for (std::int64_t x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(r * w + x);
      if (top[i] >= 0)
        paint(x + kMargin, r + kMargin, io::detail::height_colour(top[i] / zr));
      else if (top_free[i])
        paint(x + kMargin, r + kMargin, free_colour);
    }
  }
  const std::int64_t side_y0 = ht + 2 * kMargin;
  for (std::int64_t r = 0; r < hs; ++r) {
    const double height = static_cast<double>(span[2] - 1 - r * s) / zr;
    for (std::int64_t x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(r * w + x);
      if (side[i] >= 0) {
        auto c = io::detail::height_colour(height);
        const double shade = 1.0 - 0.55 * side[i] / yr;
        for (auto& ch : c) ch = static_cast<std::uint8_t>(ch * shade);
        paint(x + kMargin, side_y0 + r, c);
      } else if (side_free[i]) {
        paint(x + kMargin, side_y0 + r, free_colour);
      }
    }
  }
  // Thin frames around both views.
  auto box = [&](std::int64_t y0, std::int64_t rows) {
    for (std::int64_t x = kMargin - 1; x <= kMargin + w; ++x) {
      paint(x, y0 - 1, frame);
      paint(x, y0 + rows, frame);
    }
    for (std::int64_t y = y0 - 1; y <= y0 + rows; ++y) {
      paint(kMargin - 1, y, frame);
      paint(kMargin + w, y, frame);
    }
  };
  box(kMargin, ht);
  box(side_y0, hs);
  // Small maps: nearest-neighbour zoom so a voxel is several pixels wide.
  const std::int64_t zoom = std::clamp<std::int64_t>(1000 / (longest + 1), 1, 8);
  if (zoom > 1) {
    Picture big;
    big.voxels_per_pixel = 1;
    big.width = static_cast<std::uint32_t>(pic.width * zoom);
    big.height = static_cast<std::uint32_t>(pic.height * zoom);
    big.rgb.resize(std::size_t{big.width} * big.height * 3);
    const auto z = static_cast<std::size_t>(zoom);
    for (std::size_t y = 0; y < big.height; ++y)
      for (std::size_t x = 0; x < big.width; ++x)
        for (std::size_t c = 0; c < 3; ++c)
          big.rgb[(y * big.width + x) * 3 + c] = pic.rgb[((y / z) * pic.width + x / z) * 3 + c];
    return big;
  }
  return pic;
}

/// Renders and writes a PNG; an empty map is an io::Error naming the file.
template <class Key>
void write_map_png(const std::string& path, const OccupancyMap<Key>& map) {
  if (map.empty()) throw io::Error(path, "the map is empty: nothing to draw");
  const Picture pic = render_map_picture(map);
  io::write_png(path, pic.width, pic.height, pic.rgb);
}

}  // namespace knnocc::cli
