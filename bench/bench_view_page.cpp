// Time to draw a knnocc view page in headless Chromium (software WebGL, SwiftShader): building-like
// maps of 1e5 and 1e6 occupied voxels (rooms with floor, ceiling and walls one voxel thick), the
// page written by the tool's code, opened with the flags of the browser test. Prints the page's
// own "drawn in N ms" (from the start of navigation to the first frame finished on the GPU, the
// page's data and three.js parsed), the browser's wall time (start-up included), what the page
// drew (level, faces) and the goals (1e5 <= 3 s, 1e6 <= 8 s). There is no liboctomap counterpart
// (octovis needs a display and OpenGL). Usage: bench_view_page [repeats] [max_faces] (a larger
// face budget shows what drawing 1e6 voxels at full resolution costs).

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "../tests/headless_chromium.hpp"
#include "view_page.hpp"

using namespace knnocc;

namespace {

OccupancyMap<OcKey> rooms(std::size_t target) {
  OccupancyMap<OcKey> map(0.05);
  std::size_t n = 0;
  const int rx = 40, ry = 30, rz = 25, gap = 2;
  for (int room = 0; n < target; ++room) {
    const int ox = (room % 16) * (rx + gap) - 300, oy = (room / 16) * (ry + gap) - 300;
    for (int x = 0; x < rx && n < target; ++x)
      for (int y = 0; y < ry && n < target; ++y)
        for (int z = 0; z < rz && n < target; ++z) {
          const bool shell =
              x == 0 || x == rx - 1 || y == 0 || y == ry - 1 || z == 0 || z == rz - 1;
          if (!shell) continue;
          map.set(OcKey(static_cast<std::uint16_t>(32768 + ox + x),
                        static_cast<std::uint16_t>(32768 + oy + y),
                        static_cast<std::uint16_t>(32768 + z)),
                  2.0f);
          ++n;
        }
  }
  return map;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string chromium = test::find_chromium();
  if (chromium.empty()) {
    std::printf("bench_view_page: no Chromium found (set KNNOCC_CHROMIUM); nothing measured\n");
    return 0;
  }
  if (!cli::view_pages_available()) {
    std::printf("bench_view_page: built without three.js (libjs-three); nothing measured\n");
    return 0;
  }
  const int repeats = argc > 1 ? std::atoi(argv[1]) : 2;
  cli::ViewOptions opt;
  if (argc > 2) opt.max_faces = static_cast<std::size_t>(std::atol(argv[2]));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "knnocc_bench_view";
  std::filesystem::create_directories(dir);
  std::printf(
      "bench_view_page: %s, window 1200x800, software WebGL (SwiftShader), face budget "
      "%zu\n",
      chromium.c_str(), opt.max_faces);
  for (const std::size_t n : {std::size_t{100000}, std::size_t{1000000}}) {
    const OccupancyMap<OcKey> map = rooms(n);
    const std::string page = (dir / ("rooms_" + std::to_string(n) + ".html")).string();
    const auto t0 = std::chrono::steady_clock::now();
    const std::string html = cli::view_page_html({{"rooms", &map}}, cli::UpAxis{}, opt);
    io::AtomicFile out(page);
    out.write(html);
    out.commit();
    const double write_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::size_t level_at = html.find("\"level\":"), faces_at = html.find("\"faces\":");
    const int level = std::atoi(html.c_str() + level_at + 8);
    const long faces = std::atol(html.c_str() + faces_at + 8);
    std::printf(
        "%zu occupied voxels: page %.1f MB written in %.2f s, drawn at level %d (%g m "
        "cells), %ld exposed faces at that level\n",
        n, double(html.size()) / 1e6, write_s, level, 0.05 * (1 << level), faces);
    const double goal = n <= 100000 ? 3.0 : 8.0;
    for (int r = 0; r < repeats; ++r) {
      const test::BrowserRun run = test::run_chromium(chromium, page, "");
      const long ms = test::drawn_ms(run.dom);
      std::printf("  run %d: drawn in %ld ms (goal <= %.0f s: %s), browser wall time %.1f s\n",
                  r + 1, ms, goal, ms > 0 && ms <= goal * 1000 ? "met" : "NOT met", run.seconds);
    }
  }
  return 0;
}
