#pragma once
// Headless Chromium for the view page's browser test and benchmark: finds the browser, opens a
// page with software WebGL (SwiftShader), takes a screenshot and dumps the DOM once the page has
// loaded (the view page draws its first frame before that), and decodes PNG screenshots (zlib).

#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace knnocc::test {

/// KNNOCC_CHROMIUM, or chromium / chromium-browser / google-chrome on PATH; "" when none.
inline std::string find_chromium() {
  if (const char* e = std::getenv("KNNOCC_CHROMIUM")) return e;
  const char* path = std::getenv("PATH");
  std::string p = path ? path : "/usr/bin:/bin";
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    std::size_t start = 0;
    while (start <= p.size()) {
      const std::size_t end = std::min(p.find(':', start), p.size());
      const std::filesystem::path f = std::filesystem::path(p.substr(start, end - start)) / name;
      if (!p.substr(start, end - start).empty() && access(f.c_str(), X_OK) == 0) return f.string();
      start = end + 1;
    }
  }
  return {};
}

struct BrowserRun {
  int status = -1;
  std::string dom;     ///< the DOM after load (title: "knnocc view: drawn in N ms")
  double seconds = 0;  ///< wall time of the whole browser run, start-up included
};

/// Opens `page` in a width x height window; writes `screenshot` (PNG) when not empty.
inline BrowserRun run_chromium(const std::string& chromium, const std::string& page,
                               const std::string& screenshot, int width = 1200, int height = 800) {
  const std::filesystem::path profile =
      std::filesystem::temp_directory_path() /
      ("knnocc_chromium_" + std::to_string(getpid()) + "_" + std::to_string(std::rand()));
  std::string cmd = "timeout 300 '" + chromium +
                    "' --headless=new --no-sandbox --use-angle=swiftshader "
                    "--enable-unsafe-swiftshader --disable-extensions --no-first-run "
                    "--user-data-dir='" +
                    profile.string() + "' --window-size=" + std::to_string(width) + "," +
                    std::to_string(height);
  if (!screenshot.empty()) cmd += " --screenshot='" + screenshot + "'";
  cmd += " --dump-dom 'file://" + std::filesystem::absolute(page).string() + "' 2>/dev/null";
  BrowserRun r;
  const auto t0 = std::chrono::steady_clock::now();
  FILE* f = popen(cmd.c_str(), "r");
  if (!f) return r;
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) r.dom.append(buf, n);
  const int st = pclose(f);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::error_code ec;
  std::filesystem::remove_all(profile, ec);
  return r;
}

/// The N of "drawn in N ms" in the page's title, or -1.
inline long drawn_ms(const std::string& dom) {
  const std::string key = "drawn in ";
  const std::size_t p = dom.find(key);
  if (p == std::string::npos) return -1;
  return std::strtol(dom.c_str() + p + key.size(), nullptr, 10);
}

struct RgbImage {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // 3 bytes per pixel
};

/// Decodes an 8-bit RGB or RGBA, non-interlaced PNG (what Chromium writes); throws otherwise.
inline RgbImage decode_png_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(path + ": cannot open");
  std::string s;
  char buf[65536];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  std::fclose(f);
  auto be32 = [&](std::size_t p) {
    return (std::uint32_t(std::uint8_t(s[p])) << 24) |
           (std::uint32_t(std::uint8_t(s[p + 1])) << 16) |
           (std::uint32_t(std::uint8_t(s[p + 2])) << 8) | std::uint8_t(s[p + 3]);
  };
  if (s.size() < 8 || s.compare(0, 8, "\x89PNG\r\n\x1a\n", 8) != 0)
    throw std::runtime_error(path + ": not a PNG");
  RgbImage img;
  int channels = 0;
  std::string idat;
  for (std::size_t p = 8; p + 12 <= s.size();) {
    const std::uint32_t len = be32(p);
    const std::string type = s.substr(p + 4, 4);
    if (type == "IHDR") {
      img.width = be32(p + 8);
      img.height = be32(p + 12);
      const int depth = std::uint8_t(s[p + 16]), colour = std::uint8_t(s[p + 17]),
                interlace = std::uint8_t(s[p + 20]);
      if (depth != 8 || (colour != 2 && colour != 6) || interlace != 0)
        throw std::runtime_error(path + ": only 8-bit RGB/RGBA, non-interlaced");
      channels = colour == 2 ? 3 : 4;
    } else if (type == "IDAT") {
      idat += s.substr(p + 8, len);
    }
    p += 12 + len;
  }
  const std::size_t row = std::size_t{img.width} * static_cast<std::size_t>(channels);
  std::vector<std::uint8_t> raw((row + 1) * img.height);
  uLongf raw_size = static_cast<uLongf>(raw.size());
  if (uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()),
                 static_cast<uLong>(idat.size())) != Z_OK ||
      raw_size != raw.size())
    throw std::runtime_error(path + ": bad image data");
  std::vector<std::uint8_t> cur(row), prev(row, 0);
  img.rgb.reserve(std::size_t{img.width} * img.height * 3);
  const std::size_t bpp = static_cast<std::size_t>(channels);
  for (std::uint32_t y = 0; y < img.height; ++y) {
    const std::uint8_t filter = raw[y * (row + 1)];
    const std::uint8_t* in = &raw[y * (row + 1) + 1];
    for (std::size_t i = 0; i < row; ++i) {
      const int a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      int pred = 0;
      if (filter == 1) pred = a;
      if (filter == 2) pred = b;
      if (filter == 3) pred = (a + b) / 2;
      if (filter == 4) {
        const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
        pred = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
      }
      cur[i] = static_cast<std::uint8_t>(in[i] + pred);
    }
    for (std::uint32_t x = 0; x < img.width; ++x)
      for (std::size_t k = 0; k < 3; ++k) img.rgb.push_back(cur[x * bpp + k]);
    prev.swap(cur);
  }
  return img;
}

}  // namespace knnocc::test
