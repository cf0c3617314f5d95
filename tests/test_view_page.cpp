// knnocc view pages in a real browser: headless Chromium (software WebGL) opens a page, the page
// draws its first frame before the load event, and the screenshot must show the map: enough
// non-background pixels, the high (red) part of the scene above its low (blue) floor, for the
// page's up axis z and -y alike. Skipped when Chromium or the tool's headers are not available.

#include <doctest/doctest.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "test_support.hpp"

#ifdef KNNOCC_TEST_TOOL_HEADERS
#include <knnocc/insertion/voxel_colors.hpp>

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

// Chromium, or "" after test::skip() says why a page cannot be opened.
std::string browser_for_pages() {
  const std::string chromium = test::find_chromium();
  if (chromium.empty())
    test::skip("no Chromium (chromium, chromium-browser, google-chrome or KNNOCC_CHROMIUM)");
  else if (!cli::view_pages_available())
    test::skip("the tool was built without three.js (libjs-three)");
  else
    return chromium;
  return {};
}

}  // namespace

TEST_CASE("view_page.headless chromium draws the map upright") {
  const std::string chromium = browser_for_pages();
  if (chromium.empty()) return;
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

namespace {

// Map names a user or a file name could hold: markup with handlers, a script, an entity.
const char* const kHostileNames[] = {"<img src=x onerror=\"document.body.dataset.pwned='img'\">.bt",
                                     "<script>document.body.dataset.pwned='script'</script>",
                                     "&lt;b&gt; & \"quotes\" 'too'"};

}  // namespace

TEST_CASE("view_page.the policy lists the hash of each of the page's scripts, and only those") {
  OccupancyMap<OcKey> map(0.1);
  map.set(OcKey(32768, 32768, 32768), 2.0f);
  const std::string html = cli::view_page_html({{kHostileNames[0], &map}, {kHostileNames[1], &map}},
                                               cli::UpAxis{}, cli::ViewOptions{});
  const std::size_t csp = html.find("<meta http-equiv=\"Content-Security-Policy\" content=\"");
  REQUIRE(csp != std::string::npos);
  CHECK(csp < html.find("<script>"));  // before any script: it governs them all
  const std::string policy = html.substr(csp, html.find('>', csp) - csp);
  CHECK(policy.find("default-src 'none'") != std::string::npos);
  CHECK(policy.find("style-src 'unsafe-inline'") != std::string::npos);
  CHECK(policy.find("'unsafe-inline'") == policy.rfind("'unsafe-inline'"));  // styles only
  std::size_t scripts = 0;
  for (std::size_t p = html.find("<script>"); p != std::string::npos;
       p = html.find("<script>", p + 1)) {
    const std::size_t body = p + 8, end = html.find("</script>", body);
    REQUIRE(end != std::string::npos);
    const auto d = io::detail::sha256(html.substr(body, end - body));
    CHECK(policy.find("'sha256-" + cli::detail::base64(std::string(d.begin(), d.end())) + "'") !=
          std::string::npos);
    ++scripts;
  }
  CHECK(scripts == (cli::view_pages_available() ? 3u : 2u));
  std::size_t hashes = 0;
  for (std::size_t p = policy.find("'sha256-"); p != std::string::npos;
       p = policy.find("'sha256-", p + 1))
    ++hashes;
  CHECK(hashes == scripts);
  // The names reach the page only inside the JSON, with '<' escaped: no markup of theirs.
  CHECK(html.find("<img") == std::string::npos);
  CHECK(html.find("<script>document") == std::string::npos);
}

TEST_CASE("view_page.headless chromium shows hostile names as text and runs no script of theirs") {
  const std::string chromium = browser_for_pages();
  if (chromium.empty()) return;
  const std::filesystem::path dir = std::filesystem::path(KNNOCC_BINARY_DIR) / "view_page_test";
  std::filesystem::create_directories(dir);
  const OccupancyMap<OcKey> map = floor_and_pillar(cli::UpAxis{});
  std::vector<cli::ViewMap> maps;
  for (const char* name : kHostileNames) maps.push_back({name, &map});
  const std::string page = (dir / "hostile_names.html").string(),
                    shot = (dir / "hostile_names.png").string();
  // Every map shown first in turn (page.html#N): its name goes into the info line.
  for (std::size_t first = 0; first < maps.size(); ++first) {
    CAPTURE(first);
    cli::write_view_page(page, maps, cli::UpAxis{}, cli::ViewOptions{});
    const test::BrowserRun run =
        test::run_chromium(chromium, page + "#" + std::to_string(first), first ? "" : shot);
    REQUIRE(run.status == 0);
    CHECK(test::drawn_ms(run.dom) > 0);  // three.js and the page's script ran under the policy
    CHECK(run.dom.find("data-pwned") == std::string::npos);  // no handler, no script of a name
    CHECK(run.dom.find("<img") == std::string::npos);        // no element made from a name
    // The names as text: on the buttons, and the one shown in bold in the info line.
    const std::string text = first == 0   ? "&lt;img src=x onerror=\"document.body."
                             : first == 1 ? "&lt;script&gt;document.body."
                                          : "&amp;lt;b&amp;gt; &amp; \"quotes\" 'too'";
    CHECK(run.dom.find("<button class=\"on\">" + text) != std::string::npos);
    CHECK(run.dom.find("<div id=\"info\"><b>" + text) != std::string::npos);
  }
  // The policy itself: markup smuggled into the page (as an innerHTML would have made it) runs
  // nothing, while the page's own scripts still draw.
  std::string html = cli::view_page_html(maps, cli::UpAxis{}, cli::ViewOptions{});
  html.insert(html.rfind("</body>"),
              "<img src=x onerror=\"document.body.dataset.pwned='handler'\">"
              "<script>document.body.dataset.pwned='inline'</script>");
  const std::string injected = (dir / "injected.html").string();
  knnocc::test::write_file(injected, html);
  const test::BrowserRun run = test::run_chromium(chromium, injected, "");
  REQUIRE(run.status == 0);
  CHECK(test::drawn_ms(run.dom) > 0);
  CHECK(run.dom.find("data-pwned") == std::string::npos);
  CHECK(run.dom.find("<img src=\"x\"") != std::string::npos);  // there, and inert
}

TEST_CASE("view_page.three.js's licence notice, voxel colours and the camera path") {
  if (!cli::view_pages_available()) {
    test::skip("the tool was built without three.js (libjs-three)");
    return;
  }
  const cli::UpAxis up = cli::parse_up_axis("z");
  const OccupancyMap<OcKey> map = floor_and_pillar(up);
  VoxelColors<OcKey> colors(0.1);  // the pillar green, the floor without colour
  map.for_each_voxel([&](const OcKey& k, float) {
    if (k[2] > OcKey::center) colors.add(k, Rgb{20, 200, 40});
  });
  cli::ViewOptions opt;
  for (int i = 0; i <= 20; ++i) opt.path.push_back({-1.5 + 0.15 * i, -1.0, 1.2});
  const std::string html = cli::view_page_html({{"coloured", &map, &colors}}, up, opt);
  // MIT: the copyright and permission notice before three.js's code, once.
  const std::size_t notice = html.find("Permission is hereby granted, free of charge");
  CHECK(notice != std::string::npos);
  CHECK(html.find("three.js authors") < notice);
  CHECK(notice < html.find("THREE"));
  CHECK(html.find("Permission is hereby granted", notice + 1) == std::string::npos);
  CHECK(html.find("\"colorData\":\"") != std::string::npos);
  CHECK(html.find("\"path\":[-1.5000,1.2000,1.0000,") != std::string::npos);  // page: x, up, -fw

  const std::string chromium = test::find_chromium();
  if (chromium.empty()) {
    test::skip("no Chromium (chromium, chromium-browser, google-chrome or KNNOCC_CHROMIUM)");
    return;
  }
  const std::filesystem::path dir = std::filesystem::path(KNNOCC_BINARY_DIR) / "view_page_test";
  std::filesystem::create_directories(dir);
  const std::string page = (dir / "page_colours.html").string(),
                    shot = (dir / "page_colours.png").string();
  cli::write_view_page(page, {{"coloured", &map, &colors}}, up, opt);
  std::filesystem::remove(shot);
  const test::BrowserRun run = test::run_chromium(chromium, page, shot);
  REQUIRE(run.status == 0);
  const test::RgbImage img = test::decode_png_file(shot);
  std::size_t green = 0, red = 0, magenta = 0;
  for (std::uint32_t y = 0; y < img.height; ++y)
    for (std::uint32_t x = 0; x < img.width; ++x) {
      if ((x < 400 && y < 150) || (x > 1050 && y < 280)) continue;  // panel and legend
      const std::uint8_t* p = &img.rgb[(std::size_t{y} * img.width + x) * 3];
      green += p[1] > 110 && p[0] < 60 && p[2] < 80;
      red += p[0] > 150 && p[1] < 110 && p[2] < 90;
      magenta += p[0] > 150 && p[1] < 60 && p[2] > 90 && p[2] < 160;
    }
  MESSAGE("green ", green, ", red ", red, ", magenta ", magenta, " px; screenshot ", shot);
  CHECK(green > 300);   // the pillar in its own colour ...
  CHECK(red < 50);      // ... not in the height ramp's red
  CHECK(magenta > 30);  // the camera path
}

#else
TEST_CASE("view_page.headless chromium draws the map upright") {
  knnocc::test::skip("built without the tool (KNNOCC_BUILD_EXAMPLES=OFF)");
}
#endif
