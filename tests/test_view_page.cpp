// knnocc view pages in a real browser: headless Chromium (software WebGL) opens a page, the page
// draws its first frame before the load event, and the screenshot must show the map: enough
// non-background pixels, the high (red) part of the scene above its low (blue) floor, for the
// page's up axis z and -y alike. Skipped when Chromium or the tool's headers are not available.

#include <doctest/doctest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "test_support.hpp"

#ifdef KNNOCC_TEST_TOOL_HEADERS
#include "headless_chromium.hpp"
#include "view_page.hpp"

using namespace knnocc;

namespace {

// A 40 x 40 floor at height 0 and a 6 x 6 pillar 2.5 m high in the far corner (-x, +forward),
// in the map axes that put `up` up.
OccupancyMap<OcKey> floor_and_pillar(cli::UpAxis up) {
  OccupancyMap<OcKey> map(0.1);
  const cli::ViewFrame f(up);
  auto put = [&](int r, int fw, int u) {
    int c[3];
    c[f.axis[0]] = f.sign[0] * r;
    c[f.axis[1]] = f.sign[1] * fw;
    c[f.axis[2]] = f.sign[2] * u;
    OcKey k;
    REQUIRE(map.grid().coord_to_key(c[0] * 0.1 + 0.05, c[1] * 0.1 + 0.05, c[2] * 0.1 + 0.05, k));
    map.set(k, 2.0f);
  };
  for (int r = -20; r < 20; ++r)
    for (int fw = -20; fw < 20; ++fw) put(r, fw, 0);
  for (int r = -20; r < -14; ++r)
    for (int fw = 14; fw < 20; ++fw)
      for (int u = 1; u < 25; ++u) put(r, fw, u);
  return map;
}

struct Seen {
  std::size_t drawn = 0, red = 0, blue = 0;
  double red_y = 0, blue_y = 0;
};

Seen look(const test::RgbImage& img) {
  Seen s;
  for (std::uint32_t y = 0; y < img.height; ++y)
    for (std::uint32_t x = 0; x < img.width; ++x) {
      if ((x < 400 && y < 150) || (x > 1050 && y < 280)) continue;  // panel and legend
      const std::uint8_t* p = &img.rgb[(std::size_t{y} * img.width + x) * 3];
      const int r = p[0], g = p[1], b = p[2];
      if (std::abs(r - 244) + std::abs(g - 245) + std::abs(b - 247) > 12) ++s.drawn;
      if (r > 150 && g < 110 && b < 90) {
        ++s.red;
        s.red_y += y;
      }
      if (b > 120 && r < 90 && g < 150) {
        ++s.blue;
        s.blue_y += y;
      }
    }
  if (s.red) s.red_y /= double(s.red);
  if (s.blue) s.blue_y /= double(s.blue);
  return s;
}

}  // namespace

TEST_CASE("view_page.headless chromium draws the map upright") {
  const std::string chromium = test::find_chromium();
  if (chromium.empty()) {
    test::skip("no Chromium (chromium, chromium-browser, google-chrome or KNNOCC_CHROMIUM)");
    return;
  }
  if (!cli::view_pages_available()) {
    test::skip("the tool was built without three.js (libjs-three)");
    return;
  }
  const std::filesystem::path dir = std::filesystem::path(KNNOCC_BINARY_DIR) / "view_page_test";
  std::filesystem::create_directories(dir);
  for (const char* up_name : {"z", "-y"}) {
    CAPTURE(up_name);
    const cli::UpAxis up = cli::parse_up_axis(up_name);
    const OccupancyMap<OcKey> map = floor_and_pillar(up);
    const std::string tag = up_name[0] == '-' ? "minus_y" : "z";
    const std::string page = (dir / ("page_" + tag + ".html")).string(),
                      shot = (dir / ("page_" + tag + ".png")).string();
    cli::write_view_page(page, {{"floor and pillar", &map}}, up, cli::ViewOptions{});
    std::filesystem::remove(shot);
    const test::BrowserRun run = test::run_chromium(chromium, page, shot);
    MESSAGE("chromium exit ", run.status, ", ", run.seconds, " s, page drawn at ",
            test::drawn_ms(run.dom), " ms; screenshot ", shot);
    REQUIRE(run.status == 0);
    CHECK(test::drawn_ms(run.dom) > 0);  // the first frame was drawn (gl.finish) before load
    REQUIRE(std::filesystem::exists(shot));
    const test::RgbImage img = test::decode_png_file(shot);
    CHECK(img.width == 1200);
    CHECK(img.height == 800);
    const Seen s = look(img);
    MESSAGE("drawn ", s.drawn, " px, red ", s.red, " at y ", s.red_y, ", blue ", s.blue, " at y ",
            s.blue_y);
    CHECK(s.drawn > 20000);     // the map covers a good part of the window
    CHECK(s.red > 300);         // the pillar's top
    CHECK(s.blue > 5000);       // the floor
    CHECK(s.red_y < s.blue_y);  // high above low: up is up on the screen
  }
}

#else
TEST_CASE("view_page.headless chromium draws the map upright") {
  knnocc::test::skip("built without the tool (KNNOCC_BUILD_EXAMPLES=OFF)");
}
#endif
