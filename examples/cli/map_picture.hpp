#pragma once
// Pictures of maps (--out-png, convert .png, the demo's side-by-side image): a top view (each
// column coloured by the height of its highest occupied voxel, known-free columns light grey)
// above a side view (coloured by height, darker with depth), "up" from view_frame.hpp. The drawn
// extent is the data's robust extent (0.5 % and 99.5 % percentiles of the occupied voxels per
// axis, padded): far outliers do not shrink the map to a dot. The colour scale spans the 2 %..98 %
// height percentiles. A ceiling (a dense layer in the upper part covering >= 25 % of the
// footprint) is cut from the top view so the rooms below show. Each panel has a title line,
// a scale bar and notes on what was left out; a legend gives the colours in metres.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <knnocc/io/detail/colormap.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "bitmap_font.hpp"
#include "view_frame.hpp"
#include "zlib_png.hpp"

namespace knnocc::cli {

using Rgb = std::array<std::uint8_t, 3>;
inline constexpr Rgb kFreeColour{222, 226, 232}, kFrameColour{150, 150, 150},
    kTextColour{30, 30, 30}, kNoteColour{110, 110, 110};

/// The drawn region and colour scale, shared by the panels of one picture.
struct PictureFrame {
  ViewFrame view;
  double res = 0.1;
  std::array<std::int64_t, 3> lo{}, hi{};  // display coordinates (right, forward, up) in voxels
  std::int64_t cut = std::numeric_limits<std::int64_t>::max();  // top view shows up < cut
  bool ceiling_cut = false;
  std::int64_t colour_lo = 0, colour_hi = 1;  // heights (display up, voxels) of the colour ends
  std::int64_t step = 1;                      // voxels per pixel before zooming
  std::int64_t zoom = 1;                      // pixels per pixel after
  bool empty = true;

  /// Metres of the centre of display index d along display axis i.
  double metres(int i, double d) const { return (d + 0.5 * view.sign[i]) * res; }
  std::int64_t span(int i) const { return hi[i] - lo[i] + 1; }
  double colour_t(std::int64_t up) const {
    return static_cast<double>(up - colour_lo) /
           static_cast<double>(std::max<std::int64_t>(colour_hi - colour_lo, 1));
  }
};

namespace detail {

template <class Key>
std::array<std::int64_t, 3> display_coords(const ViewFrame& f, const Key& k) {
  std::array<std::int64_t, 3> d{};
  for (int i = 0; i < 3; ++i)
    d[i] = f.sign[i] * (static_cast<std::int64_t>(k[f.axis[i]]) - Key::center);
  return d;
}

inline std::int64_t percentile(std::vector<std::int64_t>& v, double q) {
  const auto n = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  return v[n];
}

/// A round length (1, 2 or 5 times a power of ten) near `x`.
inline double nice_length(double x) {
  const double p = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {1.0, 2.0, 5.0})
    if (m * p >= x * 0.7) return m * p;
  return 10.0 * p;
}

inline std::string metres_text(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, std::abs(m) >= 10 || m == std::round(m) ? "%.0f m" : "%.1f m", m);
  if (std::abs(m) < 1 && m != 0 && std::abs(m * 10 - std::round(m * 10)) > 1e-9)
    std::snprintf(buf, sizeof buf, "%.2f m", m);
  return buf;
}

}  // namespace detail

/// Fits the drawn region to the occupied voxels of `maps` (all at one resolution), with up along
/// `up`, at most `max_side` pixels of map per side before zooming.
template <class Key>
PictureFrame fit_picture_frame(const std::vector<const OccupancyMap<Key>*>& maps, UpAxis up,
                               std::int64_t max_side = 1000) {
  PictureFrame fr;
  fr.view = ViewFrame(up);
  std::array<std::vector<std::int64_t>, 3> c;
  for (const auto* m : maps) {
    fr.res = m->grid().resolution();
    m->for_each_voxel([&](const Key& k, float v) {
      if (!m->is_occupied(v)) return;
      const auto d = detail::display_coords(fr.view, k);
      for (int i = 0; i < 3; ++i) c[i].push_back(d[i]);
    });
  }
  if (c[0].empty()) return fr;
  fr.empty = false;
  for (int i = 0; i < 3; ++i) {
    const auto [mn, mx] = std::minmax_element(c[i].begin(), c[i].end());
    const std::int64_t lo = *mn, hi = *mx;
    std::vector<std::int64_t> v = c[i];
    const std::int64_t plo = detail::percentile(v, 0.005), phi = detail::percentile(v, 0.995);
    const std::int64_t pad = std::max<std::int64_t>(2, (phi - plo) / 20);
    fr.lo[i] = std::max(lo, plo - pad);
    fr.hi[i] = std::min(hi, phi + pad);
  }
  // Heights inside the drawn region: colour scale and ceiling.
  std::vector<std::int64_t> heights;
  std::vector<std::size_t> level(static_cast<std::size_t>(fr.span(2)), 0);
  const std::int64_t w = fr.span(0), h = fr.span(1);
  const bool columns_ok = w * h <= (std::int64_t{1} << 26);
  std::vector<std::uint8_t> column(columns_ok ? static_cast<std::size_t>(w * h) : 0, 0);
  std::size_t footprint = 0;
  for (std::size_t j = 0; j < c[0].size(); ++j) {
    const std::int64_t d[3] = {c[0][j], c[1][j], c[2][j]};
    bool in = true;
    for (int i = 0; i < 3; ++i) in = in && d[i] >= fr.lo[i] && d[i] <= fr.hi[i];
    if (!in) continue;
    heights.push_back(d[2]);
    ++level[static_cast<std::size_t>(d[2] - fr.lo[2])];
    if (columns_ok) {
      auto& col = column[static_cast<std::size_t>((d[1] - fr.lo[1]) * w + (d[0] - fr.lo[0]))];
      footprint += col == 0;
      col = 1;
    }
  }
  fr.colour_lo = detail::percentile(heights, 0.02);
  fr.colour_hi = std::max(detail::percentile(heights, 0.98), fr.colour_lo + 1);
  if (columns_ok && fr.span(2) >= 10) {
    auto dense = [&](std::int64_t u) {
      return level[static_cast<std::size_t>(u - fr.lo[2])] * 4 >= footprint;
    };
    const std::int64_t floor_of_search = fr.lo[2] + fr.span(2) * 6 / 10;
    for (std::int64_t u = fr.hi[2]; u >= floor_of_search; --u) {
      if (!dense(u)) continue;
      while (u - 1 >= floor_of_search && dense(u - 1)) --u;
      fr.cut = u;
      fr.ceiling_cut = true;
      break;
    }
  }
  const std::int64_t longest = std::max(fr.span(0), fr.span(1) + fr.span(2));
  fr.step = (longest + max_side - 1) / max_side;
  fr.zoom = std::clamp<std::int64_t>(800 / (longest / fr.step + 1), 1, 6);
  return fr;
}

namespace detail {

constexpr std::int64_t kNoVoxel = std::numeric_limits<std::int64_t>::min();

/// A map projected onto a panel's two views: per pixel the highest occupied up (top view, below
/// the cut) and the nearest forward (side view), and which pixels see free space.
struct PanelViews {
  std::int64_t w = 0, ht = 0, hs = 0;  // pixels across, top view rows, side view rows
  std::vector<std::int64_t> top, side;
  std::vector<std::uint8_t> top_free, side_free;
  std::size_t beyond = 0;  // occupied voxels outside the frame
};

template <class Key>
PanelViews project_panel(const OccupancyMap<Key>& map, const PictureFrame& fr) {
  const std::int64_t s = fr.step;
  PanelViews v;
  v.w = (fr.span(0) + s - 1) / s;
  v.ht = (fr.span(1) + s - 1) / s;
  v.hs = (fr.span(2) + s - 1) / s;
  v.top.assign(static_cast<std::size_t>(v.w * v.ht), kNoVoxel);
  v.side.assign(static_cast<std::size_t>(v.w * v.hs), kNoVoxel);
  v.top_free.assign(v.top.size(), 0);
  v.side_free.assign(v.side.size(), 0);
  map.for_each_voxel([&](const Key& k, float value) {
    const auto d = display_coords(fr.view, k);
    const bool occ = map.is_occupied(value);
    for (int i = 0; i < 3; ++i)
      if (d[i] < fr.lo[i] || d[i] > fr.hi[i]) {
        v.beyond += occ;
        return;
      }
    const std::int64_t px = (d[0] - fr.lo[0]) / s;
    const auto t = static_cast<std::size_t>((fr.hi[1] - d[1]) / s * v.w + px);
    const auto e = static_cast<std::size_t>((fr.hi[2] - d[2]) / s * v.w + px);
    if (!occ) {
      v.side_free[e] = 1;
      if (d[2] < fr.cut) v.top_free[t] = 1;
      return;
    }
    if (d[2] < fr.cut) v.top[t] = std::max(v.top[t], d[2]);
    if (v.side[e] == kNoVoxel || -d[1] > v.side[e]) v.side[e] = -d[1];  // nearest: least forward
  });
  return v;
}

/// One view of a panel at (x0, y0), framed: height colours, the side view shaded by distance.
inline void plot_view(Image& img, const PictureFrame& fr, const PanelViews& v, std::int64_t x0,
                      std::int64_t y0, bool is_top) {
  const std::int64_t s = fr.step, z = fr.zoom, w = v.w, rows = is_top ? v.ht : v.hs;
  const double yr = static_cast<double>(std::max<std::int64_t>(fr.span(1) - 1, 1));
  for (std::int64_t rr = 0; rr < rows; ++rr)
    for (std::int64_t x = 0; x < w; ++x) {
      const auto i = static_cast<std::size_t>(rr * w + x);
      Rgb col{255, 255, 255};
      if (is_top && v.top[i] != kNoVoxel) {
        col = io::detail::height_colour(fr.colour_t(v.top[i]));
      } else if (!is_top && v.side[i] != kNoVoxel) {
        col = io::detail::height_colour(fr.colour_t(fr.hi[2] - rr * s));
        const double shade = 1.0 - 0.5 * static_cast<double>(-v.side[i] - fr.lo[1]) / yr;
        for (auto& ch : col) ch = static_cast<std::uint8_t>(ch * shade);
      } else if (is_top ? v.top_free[i] : v.side_free[i]) {
        col = kFreeColour;
      } else {
        continue;
      }
      img.fill_rect(x0 + x * z, y0 + rr * z, z, z, col);
    }
  for (std::int64_t x = x0 - 1; x <= x0 + w * z; ++x) {
    img.set(x, y0 - 1, kFrameColour);
    img.set(x, y0 + rows * z, kFrameColour);
  }
  for (std::int64_t yy = y0 - 1; yy <= y0 + rows * z; ++yy) {
    img.set(x0 - 1, yy, kFrameColour);
    img.set(x0 + w * z, yy, kFrameColour);
  }
}

/// Scale bar at (x0, y0): a round length of about a quarter of a view `pw` pixels wide.
inline void draw_scale_bar(Image& img, const PictureFrame& fr, std::int64_t pw, std::int64_t x0,
                           std::int64_t y0) {
  const double px_m =
      fr.res * static_cast<double>(fr.step) / static_cast<double>(fr.zoom);  // metres/pixel
  const double len = nice_length(static_cast<double>(pw) * px_m / 4.0);
  const auto bar = static_cast<std::int64_t>(std::lround(len / px_m));
  img.fill_rect(x0, y0 + 3, bar, 2, kTextColour);
  img.fill_rect(x0, y0, 1, 8, kTextColour);
  img.fill_rect(x0 + bar - 1, y0, 1, 8, kTextColour);
  draw_text(img, x0 + bar + 5, y0 + 1, metres_text(len), kTextColour);
}

}  // namespace detail

/// One panel: title line, top view, scale bar, side view, notes.
template <class Key>
Image render_picture_panel(const OccupancyMap<Key>& map, const PictureFrame& fr,
                           const std::string& title) {
  const detail::PanelViews v = detail::project_panel(map, fr);
  const auto counts = map.count_voxels();
  char line[256];
  std::snprintf(line, sizeof line, "%g m voxels  occupied %zu  free %zu", fr.res, counts.occupied,
                counts.free);
  std::vector<std::string> notes;
  if (fr.ceiling_cut)
    notes.push_back("top view: below " + detail::metres_text(fr.metres(2, double(fr.cut) - 0.5)) +
                    " (ceiling cut)");
  if (v.beyond) notes.push_back(std::to_string(v.beyond) + " occupied beyond the drawn extent");

  const std::int64_t z = fr.zoom;
  const std::int64_t m = 10, pw = v.w * z, title_scale = text_width(title, 2) <= pw ? 2 : 1;
  const std::int64_t width =
      std::max({pw, text_width(title, static_cast<int>(title_scale)), text_width(line)}) + 2 * m;
  std::int64_t y = m;
  const std::int64_t y_line = y + 7 * title_scale + 5, y_top = y_line + 7 + 18,
                     y_scale = y_top + v.ht * z + 6, y_side = y_scale + 7 + 8 + 18,
                     height =
                         y_side + v.hs * z + 8 + static_cast<std::int64_t>(notes.size()) * 11 + m;
  Image img(static_cast<std::uint32_t>(width), static_cast<std::uint32_t>(height));
  draw_text(img, m, y, title, kTextColour, static_cast<int>(title_scale));
  draw_text(img, m, y_line, line, kNoteColour);
  const std::string r = std::string(fr.view.sign[0] < 0 ? "-" : "") + char('x' + fr.view.axis[0]),
                    f = std::string(fr.view.sign[1] < 0 ? "-" : "") + char('x' + fr.view.axis[1]);
  draw_text(img, m, y_top - 11, "top view (" + r + " right, " + f + " up)", kNoteColour);
  draw_text(img, m, y_side - 11, "side view (" + r + " right, " + fr.view.up.name() + " up)",
            kNoteColour);
  detail::plot_view(img, fr, v, m, y_top, true);
  detail::plot_view(img, fr, v, m, y_side, false);
  detail::draw_scale_bar(img, fr, pw, m, y_scale);
  for (std::size_t i = 0; i < notes.size(); ++i)
    draw_text(img, m, y_side + v.hs * z + 8 + static_cast<std::int64_t>(i) * 11, notes[i],
              kNoteColour);
  return img;
}

/// The colour legend: height in metres along the up axis, and the free colour.
inline Image render_picture_legend(const PictureFrame& fr, std::int64_t bar_height = 200) {
  const std::int64_t m = 10, bw = 16;
  Image img(static_cast<std::uint32_t>(125), static_cast<std::uint32_t>(bar_height + 3 * m + 40));
  draw_text(img, m, m, "height (" + fr.view.up.name() + ")", kTextColour);
  const std::int64_t y0 = m + 14;
  for (std::int64_t y = 0; y < bar_height; ++y)
    img.fill_rect(m, y0 + y, bw, 1,
                  io::detail::height_colour(1.0 - static_cast<double>(y) / double(bar_height - 1)));
  const double lo = fr.metres(2, static_cast<double>(fr.colour_lo)),
               hi = fr.metres(2, static_cast<double>(fr.colour_hi));
  const double tick = detail::nice_length(std::max(hi - lo, fr.res) / 4.0);
  for (double v = std::ceil(lo / tick) * tick; v <= hi + 1e-9; v += tick) {
    const auto y = y0 + static_cast<std::int64_t>(std::lround((hi - v) / (hi - lo) *
                                                              static_cast<double>(bar_height - 1)));
    img.fill_rect(m + bw, y, 4, 1, kTextColour);
    draw_text(img, m + bw + 7, y - 3, detail::metres_text(std::abs(v) < 1e-9 ? 0.0 : v),
              kTextColour);
  }
  const std::int64_t yf = y0 + bar_height + m;
  img.fill_rect(m, yf, bw, 10, kFreeColour);
  draw_text(img, m + bw + 7, yf + 2, "free", kTextColour);
  draw_text(img, m, yf + 18, "clipped to 2-98 %", kNoteColour);
  return img;
}

/// Panels side by side, top-aligned, with the legend at the right.
inline Image side_by_side(const std::vector<Image>& parts) {
  std::int64_t w = 0, h = 0;
  for (const Image& p : parts) {
    w += p.width;
    h = std::max<std::int64_t>(h, p.height);
  }
  Image out(static_cast<std::uint32_t>(w), static_cast<std::uint32_t>(h));
  std::int64_t x = 0;
  for (const Image& p : parts) {
    out.blit(p, x, 0);
    x += p.width;
  }
  return out;
}

/// Picture of one map (title: what it is, e.g. "OctoMap model"); io::Error naming `path` when
/// the map has no occupied voxel.
template <class Key>
Image render_map_picture(const OccupancyMap<Key>& map, UpAxis up, const std::string& title,
                         const std::string& path = "<picture>") {
  const PictureFrame fr = fit_picture_frame<Key>({&map}, up);
  if (fr.empty) throw io::Error(path, "the map has no occupied voxel: nothing to draw");
  const Image panel = render_picture_panel(map, fr, title);
  return side_by_side(
      {panel, render_picture_legend(
                  fr, std::min<std::int64_t>(200, std::max<std::int64_t>(80, panel.height - 90)))});
}

template <class Key>
void write_map_png(const std::string& path, const OccupancyMap<Key>& map, UpAxis up,
                   const std::string& title) {
  const Image img = render_map_picture(map, up, title, path);
  write_png_compressed(path, img.width, img.height, img.rgb);
}

/// Several maps side by side in one picture, all with the same extent and colour scale (fitted
/// to all of them), and one legend: e.g. OctoMap model | k-NN model | reference.
inline void write_comparison_png(
    const std::string& path,
    const std::vector<std::pair<std::string, const OccupancyMap<OcKey>*>>& maps, UpAxis up) {
  using Key = OcKey;
  std::vector<const OccupancyMap<Key>*> ptrs;
  for (const auto& m : maps) ptrs.push_back(m.second);
  const PictureFrame fr = fit_picture_frame<Key>(ptrs, up, 400);
  if (fr.empty) throw io::Error(path, "the maps have no occupied voxel: nothing to draw");
  std::vector<Image> parts;
  std::int64_t h = 0;
  for (const auto& m : maps) {
    parts.push_back(render_picture_panel(*m.second, fr, m.first));
    h = std::max<std::int64_t>(h, parts.back().height);
  }
  parts.push_back(render_picture_legend(fr, std::clamp<std::int64_t>(h - 90, 80, 200)));
  const Image img = side_by_side(parts);
  write_png_compressed(path, img.width, img.height, img.rgb);
}

}  // namespace knnocc::cli
