#pragma once
// Heat maps of the sensitivity grid (sim/sensitivity_grid.hpp): per model one PNG with two rows
// of panels, irrelevant nodes (% of the OctoMap model's) and F1 (the authors' counting), each a
// panel per re-observation probability: patch size across, lifetime down, the value printed in
// every cell; the mixed regime's values under them. Written with io/png.hpp (deflated by the
// tool's zlib when built with it), labelled with the tool's bitmap font.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include <knnocc/io/png.hpp>
#include <knnocc/sim/sensitivity_grid.hpp>

#include "bitmap_font.hpp"
#include "zlib_png.hpp"

namespace knnocc::bench {

using Rgb = std::array<std::uint8_t, 3>;

// Irrelevant share: 0 green, 10 light green, 25 yellow, 100 red, beyond it dark red.
inline Rgb share_colour(double pct) {
  if (std::isnan(pct)) return {200, 200, 200};
  struct Stop {
    double at;
    Rgb c;
  };
  static const Stop stops[] = {{0, {26, 152, 80}},   {10, {166, 217, 106}}, {25, {254, 224, 139}},
                               {60, {244, 109, 67}}, {100, {215, 48, 39}},  {200, {120, 0, 20}}};
  const double v = std::clamp(pct, 0.0, 200.0);
  for (std::size_t i = 1; i < std::size(stops); ++i)
    if (v <= stops[i].at) {
      const double t = (v - stops[i - 1].at) / (stops[i].at - stops[i - 1].at);
      Rgb c;
      for (int k = 0; k < 3; ++k)
        c[std::size_t(k)] = static_cast<std::uint8_t>(
            std::lround(stops[i - 1].c[std::size_t(k)] +
                        t * (stops[i].c[std::size_t(k)] - stops[i - 1].c[std::size_t(k)])));
      return c;
    }
  return stops[std::size(stops) - 1].c;
}

// F1 in [0, 1]: 0.5 and below red, up to 1 green.
inline Rgb f1_colour(double f1) {
  if (std::isnan(f1)) return {200, 200, 200};
  return share_colour(100.0 * std::clamp((1.0 - f1) / 0.5, 0.0, 1.0));
}

struct HeatMapValues {
  std::vector<sim::GridCell> cells;
  std::vector<double> irrelevant_pct, f1;  ///< per cell (NaN: not run)
};

/// Writes the heat map of one model to `path` (throws io::Error when it cannot).
inline void write_heat_map(const std::string& path, const std::string& title,
                           const HeatMapValues& v) {
  constexpr int cw = 52, ch = 24, scale = 1, left = 62, top = 48, gap = 34, label = 30;
  const int nx = int(sim::kGridPatchSizes.size()), ny = int(sim::kGridLifetimes.size());
  const int panel_w = nx * cw, panel_h = ny * ch;
  const int width = left + 2 * panel_w + gap + 12;
  const int height = top + 2 * panel_h + label + gap + label + 20;
  cli::Image img(std::uint32_t(width), std::uint32_t(height), 255);
  const Rgb black{0, 0, 0}, white{255, 255, 255};
  cli::draw_text(img, 8, 6, title, black, 1);
  auto text_on = [&](const Rgb& bg) {
    return (bg[0] * 299 + bg[1] * 587 + bg[2] * 114) / 1000 < 120 ? white : black;
  };
  char buf[128];
  for (int row = 0; row < 2; ++row) {  // 0: irrelevant share, 1: F1
    const int y0 = top + row * (panel_h + label + gap);
    cli::draw_text(img, 8, y0 - 30,
                   row == 0 ? "irrelevant nodes, % of the OctoMap model's (lower is better)"
                            : "F1, authors' counting (higher is better)",
                   black, 1);
    for (int pr = 0; pr < 2; ++pr) {
      const int x0 = left + pr * (panel_w + gap);
      std::snprintf(buf, sizeof buf, "re-observed with p = %g", sim::kGridProbabilities[pr]);
      cli::draw_text(img, x0, y0 - 14, buf, black, 1);
      for (int i = 0; i < nx; ++i) {
        std::snprintf(buf, sizeof buf, "%zu", sim::kGridPatchSizes[std::size_t(i)]);
        cli::draw_text(img, x0 + i * cw + cw / 2 - 3, y0 + panel_h + 4, buf, black, 1);
      }
      for (int j = 0; j < ny; ++j) {
        std::snprintf(buf, sizeof buf, "%zu", sim::kGridLifetimes[std::size_t(j)]);
        cli::draw_text(img, x0 - 6 - int(cli::text_width(buf)), y0 + j * ch + ch / 2 - 3, buf,
                       black, 1);
      }
      for (std::size_t c = 0; c < v.cells.size(); ++c) {
        const sim::GridCell& g = v.cells[c];
        if (g.mixed || g.probability != sim::kGridProbabilities[std::size_t(pr)]) continue;
        int i = 0, j = 0;
        while (sim::kGridPatchSizes[std::size_t(i)] != g.patch) ++i;
        while (sim::kGridLifetimes[std::size_t(j)] != g.lifetime) ++j;
        const double val = row == 0 ? v.irrelevant_pct[c] : v.f1[c];
        const Rgb bg = row == 0 ? share_colour(val) : f1_colour(val);
        img.fill_rect(x0 + i * cw + 1, y0 + j * ch + 1, cw - 2, ch - 2, bg);
        if (std::isnan(val))
          std::snprintf(buf, sizeof buf, "-");
        else
          std::snprintf(buf, sizeof buf, row == 0 ? "%.0f" : "%.2f", val);
        cli::draw_text(img, x0 + i * cw + (cw - int(cli::text_width(buf))) / 2,
                       y0 + j * ch + ch / 2 - 3, buf, text_on(bg), scale);
      }
    }
    cli::draw_text(img, 2, y0 + panel_h / 2 - 12, "life-", black, 1);
    cli::draw_text(img, 2, y0 + panel_h / 2 - 2, "time", black, 1);
    cli::draw_text(img, left + panel_w - 30, y0 + panel_h + 16, "patch size", black, 1);
    cli::draw_text(img, left + 2 * panel_w + gap - 60, y0 + panel_h + 16, "patch size", black, 1);
  }
  for (std::size_t c = 0; c < v.cells.size(); ++c)
    if (v.cells[c].mixed) {
      std::snprintf(buf, sizeof buf, "mixed regime: irrelevant %.0f %%, F1 %.2f",
                    v.irrelevant_pct[c], v.f1[c]);
      cli::draw_text(img, 8, height - 16, buf, black, 1);
    }
  io::write_png(path, img.width, img.height, img.rgb, cli::zlib_deflate());
}

}  // namespace knnocc::bench
