#pragma once
// knnocc view pages: one self-contained HTML file (three.js embedded, no network at view time)
// that shows maps in 3D. The occupied voxels are sent as cells with a mask of their exposed faces
// (a face between two occupied cells is never drawn) and drawn as instanced quads, coloured by
// height in the vertex shader. When a map has more exposed faces than the budget, the page draws
// a coarser level (cells of 2, 4, ... voxels: a cell is occupied when any voxel in it is) and
// says so; free voxels (on a toggle) are points, coarsened the same way. A map with voxel colours
// (VoxelColors) sends a colour per drawn cell (the mean of its coloured voxels' colours) and the
// page offers colour or height; a camera path is drawn as a line. three.js's licence notice goes
// with the embedded script.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include <knnocc/insertion/voxel_colors.hpp>
#include <knnocc/io/atomic_file.hpp>
#include <knnocc/io/detail/sha256.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/map/occupancy_map.hpp>

#include "view_frame.hpp"
#include "view_page_script.hpp"

#ifdef KNNOCC_TOOL_THREE_JS
#include "knnocc_three_js.hpp"
#endif

namespace knnocc::cli {

struct ViewMap {
  std::string name;
  const OccupancyMap<OcKey>* map = nullptr;
  const VoxelColors<OcKey>* colors = nullptr;  ///< the occupied voxels' colours, if any
};

struct ViewOptions {
  std::size_t max_faces = 2500000;  ///< exposed faces drawn per map before coarsening
  std::size_t max_free = 300000;    ///< free cells drawn per map before coarsening
  std::vector<Point3d> path;        ///< camera positions (world frame), drawn as a line
};

/// Whether this build can write pages (three.js found at configure time).
inline bool view_pages_available() {
#ifdef KNNOCC_TOOL_THREE_JS
  return true;
#else
  return false;
#endif
}

namespace detail {

inline std::string base64(const std::string& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t(std::uint8_t(in[i])) << 16) |
                            (std::uint32_t(std::uint8_t(in[i + 1])) << 8) | std::uint8_t(in[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += t[(v >> s) & 63u];
  }
  if (i < in.size()) {
    std::uint32_t v = std::uint32_t(std::uint8_t(in[i])) << 16;
    if (i + 1 < in.size()) v |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
    out += t[(v >> 18) & 63u];
    out += t[(v >> 12) & 63u];
    out += i + 1 < in.size() ? t[(v >> 6) & 63u] : '=';
    out += '=';
  }
  return out;
}

inline void put_u16(std::string& s, std::int64_t v) {
  s += static_cast<char>(v & 0xFF);
  s += static_cast<char>((v >> 8) & 0xFF);
}

inline std::uint64_t pack_cell(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (static_cast<std::uint64_t>(x) << 42) | (static_cast<std::uint64_t>(y) << 21) |
         static_cast<std::uint64_t>(z);
}

/// Cells (page axes: X right, Y up, Z towards the viewer) of one map at one level.
struct PageCells {
  int level = 0;
  std::string cells, masks;  // u16 x 3 per cell; exposed-face bits +X -X +Y -Y +Z -Z
  std::string colors;        // r g b a per drawn cell (a = 0: no colour) when the map has them
  std::size_t count = 0, faces = 0;
};

/// The colour sums and counts of the coloured voxels in each cell (`rgb[i]` belongs to `vox[i]`;
/// a = 0 when the voxel has none; no `rgb` at all: no colours).
inline std::unordered_map<std::uint64_t, std::array<std::uint32_t, 4>> cell_colors(
    const std::vector<std::array<std::int64_t, 3>>& vox,
    const std::vector<std::array<std::uint8_t, 4>>& rgb, int level) {
  std::unordered_map<std::uint64_t, std::array<std::uint32_t, 4>> sums;
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    if (!rgb[i][3]) continue;
    auto& s = sums[pack_cell(vox[i][0] >> level, vox[i][1] >> level, vox[i][2] >> level)];
    for (int c = 0; c < 3; ++c) s[c] += rgb[i][c];
    ++s[3];
  }
  return sums;
}

inline PageCells occupied_cells(const std::vector<std::array<std::int64_t, 3>>& vox,
                                const std::vector<std::array<std::uint8_t, 4>>& rgb, int level) {
  std::unordered_set<std::uint64_t> set;
  set.reserve(vox.size());
  for (const auto& v : vox) set.insert(pack_cell(v[0] >> level, v[1] >> level, v[2] >> level));
  const auto colors = cell_colors(vox, rgb, level);
  std::vector<std::uint64_t> sorted(set.begin(), set.end());
  std::sort(sorted.begin(), sorted.end());
  PageCells pc;
  pc.level = level;
  pc.count = sorted.size();
  const std::uint64_t m = (std::uint64_t{1} << 21) - 1;
  for (const std::uint64_t c : sorted) {
    const auto x = static_cast<std::int64_t>(c >> 42), y = static_cast<std::int64_t>((c >> 21) & m),
               z = static_cast<std::int64_t>(c & m);
    int mask = 0;
    const std::int64_t nb[6][3] = {{x + 1, y, z}, {x - 1, y, z}, {x, y + 1, z},
                                   {x, y - 1, z}, {x, y, z + 1}, {x, y, z - 1}};
    for (int f = 0; f < 6; ++f) {
      const bool outside = nb[f][0] < 0 || nb[f][1] < 0 || nb[f][2] < 0;
      if (outside || !set.count(pack_cell(nb[f][0], nb[f][1], nb[f][2]))) {
        mask |= 1 << f;
        ++pc.faces;
      }
    }
    if (!mask) continue;  // interior: nothing to draw
    put_u16(pc.cells, x);
    put_u16(pc.cells, y);
    put_u16(pc.cells, z);
    pc.masks += static_cast<char>(mask);
    if (rgb.empty()) continue;
    const auto it = colors.find(c);
    const std::array<std::uint32_t, 4> sum =
        it == colors.end() ? std::array<std::uint32_t, 4>{} : it->second;
    for (int k = 0; k < 3; ++k)  // the mean, rounded
      pc.colors += static_cast<char>(sum[3] ? (2 * sum[k] + sum[3]) / (2 * sum[3]) : 0);
    pc.colors += static_cast<char>(sum[3] ? 255 : 0);
  }
  return pc;
}

inline double percentile_of(std::vector<double> v, double q) {
  const auto n = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  return v[n];
}

inline std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (c == '<') {
      o += "\\u003c";
      continue;
    }
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {  // a name's tab or newline kept
      char u[8];
      std::snprintf(u, sizeof u, "\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      o += u;
      continue;
    }
    o += c;
  }
  return o + "\"";
}

/// A meta element that lets the page run its own inline scripts (by their SHA-256) and nothing
/// else: no other script, no event handler attribute, no network, no plugin; inline styles stay.
inline std::string content_security_policy(const std::vector<std::string>& scripts) {
  std::string sources;
  for (const std::string& s : scripts) {
    const auto digest = io::detail::sha256(s);
    sources += " 'sha256-" + base64(std::string(digest.begin(), digest.end())) + "'";
  }
  return "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; script-src" +
         sources + "; style-src 'unsafe-inline'; base-uri 'none'; form-action 'none'\">\n";
}

}  // namespace detail

namespace detail {

/// A map's voxels in page coordinates (X right, Y up, Z -forward; three.js is right-handed with
/// Y up), shifted so that the least index per axis is 0 (`lo` holds the shift).
struct PageVoxels {
  std::vector<std::array<std::int64_t, 3>> occ, fre;
  std::vector<std::array<std::uint8_t, 4>> rgb;  // per occupied voxel with `colors`; a = 0: none
  std::array<std::int64_t, 3> lo{};
};

inline PageVoxels page_voxels(const OccupancyMap<OcKey>& map, const VoxelColors<OcKey>* colors,
                              const std::array<int, 3>& axis, const std::array<int, 3>& sign) {
  PageVoxels pv;
  map.for_each_voxel([&](const OcKey& k, float v) {
    std::array<std::int64_t, 3> d{};
    for (int i = 0; i < 3; ++i)
      d[i] = sign[i] * (static_cast<std::int64_t>(k[axis[i]]) - OcKey::center);
    if (!map.is_occupied(v)) return pv.fre.push_back(d);
    pv.occ.push_back(d);
    if (!colors) return;
    const std::optional<knnocc::Rgb> c = colors->mean(k);
    pv.rgb.push_back(c ? std::array<std::uint8_t, 4>{c->r, c->g, c->b, 255}
                       : std::array<std::uint8_t, 4>{0, 0, 0, 0});
  });
  for (int i = 0; i < 3; ++i) {
    pv.lo[i] = std::numeric_limits<std::int64_t>::max();
    for (const auto* set : {&pv.occ, &pv.fre})
      for (const auto& d : *set) pv.lo[i] = std::min(pv.lo[i], d[i]);
  }
  for (auto* set : {&pv.occ, &pv.fre})
    for (auto& d : *set)
      for (int i = 0; i < 3; ++i) d[i] -= pv.lo[i];
  return pv;
}

/// Free cells, coarsened until there are at most `max_free`; cells holding an occupied voxel are
/// left out. `bytes`: the sorted cells as three 16-bit indices each.
struct FreeCells {
  int level = 0;
  std::size_t count = 0;
  std::string bytes;
};

inline FreeCells free_cells(const PageVoxels& pv, std::size_t max_free) {
  FreeCells fc;
  std::vector<std::uint64_t> cells;
  for (; fc.level <= 16; ++fc.level) {
    const int l = fc.level;
    std::unordered_set<std::uint64_t> occ_cells, seen;
    for (const auto& d : pv.occ) occ_cells.insert(pack_cell(d[0] >> l, d[1] >> l, d[2] >> l));
    cells.clear();
    for (const auto& d : pv.fre) {
      const auto c = pack_cell(d[0] >> l, d[1] >> l, d[2] >> l);
      if (!occ_cells.count(c) && seen.insert(c).second) cells.push_back(c);
    }
    if (cells.size() <= max_free) break;
  }
  std::sort(cells.begin(), cells.end());
  const std::uint64_t m21 = (std::uint64_t{1} << 21) - 1;
  for (const std::uint64_t c : cells) {
    put_u16(fc.bytes, static_cast<std::int64_t>(c >> 42));
    put_u16(fc.bytes, static_cast<std::int64_t>((c >> 21) & m21));
    put_u16(fc.bytes, static_cast<std::int64_t>(c & m21));
  }
  fc.count = cells.size();
  return fc;
}

/// One map's entry of the page's data; the heights of its occupied voxels go to `heights`.
inline std::string map_json(const ViewMap& vm, const std::array<int, 3>& page_axis,
                            const std::array<int, 3>& page_sign, const ViewOptions& opt,
                            std::vector<double>& heights) {
  const auto& map = *vm.map;
  const double res = map.grid().resolution();
  const PageVoxels pv = page_voxels(map, vm.colors, page_axis, page_sign);
  PageCells pc;
  for (int level = 0; level <= 16; ++level) {
    pc = occupied_cells(pv.occ, pv.rgb, level);
    if (pc.faces <= opt.max_faces) break;
  }
  const FreeCells fc = free_cells(pv, opt.max_free);
  // Metres of voxel index 0 (its lower corner) per page axis: a voxel with display index d
  // spans [d, d + 1] * res when the axis keeps the map's sign, [d - 1, d] * res otherwise.
  std::array<double, 3> origin{};
  for (int i = 0; i < 3; ++i)
    origin[i] = static_cast<double>(pv.lo[i] + (page_sign[i] < 0 ? -1 : 0)) * res;
  // Robust centre and size for the camera (outliers do not push the map out of view).
  std::array<double, 3> centre{}, half{};
  for (int i = 0; i < 3; ++i) {
    std::vector<double> v;
    v.reserve(pv.occ.size());
    for (const auto& d : pv.occ) v.push_back((static_cast<double>(d[i]) + 0.5) * res + origin[i]);
    const double a = percentile_of(v, 0.01), b = percentile_of(v, 0.99);
    centre[i] = 0.5 * (a + b);
    half[i] = 0.5 * (b - a) + res;
    if (i == 1) heights.insert(heights.end(), v.begin(), v.end());
  }
  const auto counts = map.count_voxels();
  char buf[1024];
  std::snprintf(buf, sizeof buf,
                "{\"name\":%s,\"res\":%.9g,\"occupied\":%zu,\"free\":%zu,\"level\":%d,"
                "\"cells\":%zu,\"drawnCells\":%zu,\"faces\":%zu,\"freeLevel\":%d,"
                "\"freeCells\":%zu,\"origin\":[%.9g,%.9g,%.9g],\"centre\":[%.6g,%.6g,%.6g],"
                "\"half\":[%.6g,%.6g,%.6g],",
                json_string(vm.name).c_str(), res, counts.occupied, counts.free, pc.level, pc.count,
                pc.masks.size(), pc.faces, fc.level, fc.count, origin[0], origin[1], origin[2],
                centre[0], centre[1], centre[2], half[0], half[1], half[2]);
  std::string json = std::string(buf) + "\"cellData\":\"" + base64(pc.cells) +
                     "\",\"maskData\":\"" + base64(pc.masks) + "\",\"freeData\":\"" +
                     base64(fc.bytes) + "\"";
  if (!pc.colors.empty()) json += ",\"colorData\":\"" + base64(pc.colors) + "\"";
  return json + "}";
}

/// The camera path in page coordinates (metres): [x,y,z,x,y,z,...].
inline std::string path_json(const std::vector<Point3d>& path, const std::array<int, 3>& axis,
                             const std::array<int, 3>& sign) {
  std::string json = "[";
  for (const Point3d& p : path) {
    const double w[3] = {p.x, p.y, p.z};
    char buf[96];
    std::snprintf(buf, sizeof buf, "%s%.4f,%.4f,%.4f", json.size() > 1 ? "," : "",
                  sign[0] * w[axis[0]], sign[1] * w[axis[1]], sign[2] * w[axis[2]]);
    json += buf;
  }
  return json + "]";
}

#ifdef KNNOCC_TOOL_THREE_JS
/// three.js with its licence notice first (MIT: the notice goes with every copy).
inline std::string three_js_script() {
  std::string js = std::string("\n/*! ") + kThreeJsNotice + "*/\n";
  for (const char* piece : kThreeJsPieces) js += piece;
  return js + "\n";
}
#endif

}  // namespace detail

/// The whole page for `maps` (at least one, each with an occupied voxel).
inline std::string view_page_html(const std::vector<ViewMap>& maps, UpAxis up,
                                  const ViewOptions& opt) {
  const ViewFrame vf(up);
  // Page axes: X = right, Y = up, Z = -forward (three.js is right-handed with Y up).
  const std::array<int, 3> page_axis{vf.axis[0], vf.axis[2], vf.axis[1]};
  const std::array<int, 3> page_sign{vf.sign[0], vf.sign[2], -vf.sign[1]};
  std::vector<double> all_heights;
  std::string maps_json;
  for (const ViewMap& vm : maps)
    maps_json += std::string(maps_json.empty() ? "" : ",\n") +
                 detail::map_json(vm, page_axis, page_sign, opt, all_heights);
  const double h_lo = detail::percentile_of(all_heights, 0.02),
               h_hi = std::max(detail::percentile_of(all_heights, 0.98), h_lo + 1e-3);
  auto axis_name = [](int a, int s) { return std::string(s < 0 ? "-" : "") + char('x' + a); };
  char head[512];
  std::snprintf(head, sizeof head,
                "{\"up\":\"%s\",\"right\":\"%s\",\"forward\":\"%s\",\"heightLo\":%.6g,"
                "\"heightHi\":%.6g,\"maxFaces\":%zu,\"path\":",
                up.name().c_str(), axis_name(vf.axis[0], vf.sign[0]).c_str(),
                axis_name(vf.axis[1], vf.sign[1]).c_str(), h_lo, h_hi, opt.max_faces);
  std::vector<std::string> scripts;
#ifdef KNNOCC_TOOL_THREE_JS
  scripts.push_back(detail::three_js_script());
#endif
  scripts.push_back("\nconst KNNOCC_DATA = " + std::string(head) +
                    detail::path_json(opt.path, page_axis, page_sign) + ",\"maps\":[\n" +
                    maps_json + "]};\n");
  scripts.emplace_back(detail::kViewPageScript);
  std::string html = "<!doctype html>\n<html><head><meta charset=\"utf-8\">\n" +
                     detail::content_security_policy(scripts) + detail::kViewPageHead;
  for (const std::string& s : scripts) html += "<script>" + s + "</script>\n";
  return html + "</body></html>\n";
}

/// Writes the page atomically; io::Error naming `path` for an empty map or a build without
/// three.js.
inline void write_view_page(const std::string& path, const std::vector<ViewMap>& maps, UpAxis up,
                            const ViewOptions& opt) {
  if (!view_pages_available())
    throw io::Error(path,
                    "this knnocc was built without three.js (install libjs-three and "
                    "configure again)");
  for (const ViewMap& vm : maps)
    if (vm.map->count_voxels().occupied == 0)
      throw io::Error(path, "map '" + vm.name + "' has no occupied voxel: nothing to draw");
  io::AtomicFile out(path);
  out.write(view_page_html(maps, up, opt));
  out.commit();
}

}  // namespace knnocc::cli
