// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS map_server maps (what map_server, map_saver and Nav2's map_server load): NAME.yaml plus
// the image it names, here NAME.pgm (binary greyscale "P5").
//
//   image: "NAME.pgm"         double-quoted and escaped: any file name reads back as itself
//   mode: trinary
//   resolution: 0.05
//   origin: [x, y, 0.0]       the outer corner of the bottom-left pixel, yaw 0
//   negate: 0
//   occupied_thresh: 0.65
//   free_thresh: 0.196
//
// Pixels are map_saver's: 0 occupied, 254 free, 205 unknown; the image's first row is the top of
// the map (the largest y). With negate 0 a loader takes p = (255 - pixel) / 255 and calls a cell
// occupied when p > occupied_thresh, free when p < free_thresh: 0 -> 1.0 occupied, 254 -> 0.004
// free, 205 -> 0.19608 unknown (just above 0.196, which is why map_saver writes that value).
//
// write_ros_map writes both files atomically, as a set. read_ros_map reads them back (this
// writer's files and map_saver's: any P5 image with maxval 255, trinary thresholds applied).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "../map/occupancy_grid_2d.hpp"
#include "atomic_file.hpp"
#include "detail/file_text.hpp"
#include "detail/yaml_scalar.hpp"
#include "error.hpp"

namespace knnocc::io {

inline constexpr std::uint8_t kRosOccupiedPixel = 0, kRosFreePixel = 254, kRosUnknownPixel = 205;

/// The image path a map's YAML names: NAME.yaml -> NAME.pgm beside it.
inline std::string ros_map_image_path(const std::string& yaml_path) {
  return std::filesystem::path(yaml_path).replace_extension(".pgm").string();
}

/// The image name as the YAML's `image:` value (a double-quoted scalar); io::Error naming the
/// YAML when the name is not valid UTF-8 (no YAML text can name that file). The tool calls it
/// before any work.
inline std::string ros_map_image_entry(const std::string& yaml_path) {
  const std::string name = std::filesystem::path(ros_map_image_path(yaml_path)).filename().string();
  std::string quoted;
  if (!detail::yaml_double_quoted(name, quoted))
    throw Error(yaml_path, "the image name '" + name +
                               "' is not valid UTF-8, which a YAML file cannot name; choose "
                               "another name");
  return quoted;
}

/// Writes NAME.yaml and NAME.pgm (see the file comment); inside an open CommitGroup the two
/// files join it, else they are committed together here. An empty grid is an io::Error.
inline void write_ros_map(const std::string& yaml_path, const OccupancyGrid2D& grid) {
  if (grid.empty()) throw Error(yaml_path, "the 2D grid is empty: nothing to write");
  const std::string image = ros_map_image_path(yaml_path);
  const std::string image_entry = ros_map_image_entry(yaml_path);
  std::string pgm = "P5\n# knnocc occupancy grid, " + std::to_string(grid.resolution) +
                    " m/pixel\n" + std::to_string(grid.width) + " " + std::to_string(grid.height) +
                    "\n255\n";
  const std::size_t header = pgm.size();
  pgm.resize(header + grid.width * grid.height);
  for (std::size_t row = 0; row < grid.height; ++row) {
    const std::size_t y = grid.height - 1 - row;  // the first row is the top
    for (std::size_t x = 0; x < grid.width; ++x) {
      const std::int8_t c = grid.at(x, y);
      pgm[header + row * grid.width + x] =
          static_cast<char>(c == OccupancyGrid2D::kOccupied ? kRosOccupiedPixel
                            : c == OccupancyGrid2D::kFree   ? kRosFreePixel
                                                            : kRosUnknownPixel);
    }
  }
  char numbers[256];
  std::snprintf(numbers, sizeof numbers,
                "mode: trinary\nresolution: %.9g\norigin: [%.9g, %.9g, 0.0]\nnegate: 0\n"
                "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
                grid.resolution, grid.origin[0], grid.origin[1]);
  const std::string yaml = "image: " + image_entry + "\n" + numbers;
  std::optional<CommitGroup> group;
  if (!detail::current_group()) group.emplace();
  AtomicFile pgm_file(image);
  pgm_file.write(pgm);
  pgm_file.commit();
  AtomicFile yaml_file(yaml_path);
  yaml_file.write(yaml);
  yaml_file.commit();
  if (group) group->commit();
}

namespace detail {

// One "key: value" line of a map YAML (the flat subset map_saver writes); false for others.
inline bool yaml_entry(const char* b, const char* e, std::string& key, std::string& value) {
  while (b != e && is_blank(*b)) ++b;
  if (b == e || *b == '#') return false;
  const char* colon = b;
  while (colon != e && *colon != ':') ++colon;
  if (colon == e) return false;
  key.assign(b, colon);
  const char* v = colon + 1;
  while (v != e && is_blank(*v)) ++v;
  const char* ve = e;
  while (ve != v && is_blank(ve[-1])) --ve;
  value.assign(v, ve);
  return true;
}

// The P5 image's pixels (maxval 255), row by row from the top.
inline std::vector<std::uint8_t> read_pgm(const std::string& path, std::size_t& width,
                                          std::size_t& height) {
  const FileBuffer buf = read_file(path);
  const char* p = buf.data();
  const char* const end = buf.end();
  const auto token = [&]() {
    while (p != end && (is_space(*p) || *p == '#')) {
      if (*p == '#')
        while (p != end && *p != '\n') ++p;
      else
        ++p;
    }
    const char* b = p;
    while (p != end && !is_space(*p)) ++p;
    return std::string(b, p);
  };
  if (token() != "P5") throw Error(path, "not a binary PGM image (no 'P5' magic)");
  std::uint64_t w = 0, h = 0, maxval = 0;
  const std::string ws = token(), hs = token(), ms = token();
  if (!parse_int_token(ws.data(), ws.data() + ws.size(), w) ||
      !parse_int_token(hs.data(), hs.data() + hs.size(), h) ||
      !parse_int_token(ms.data(), ms.data() + ms.size(), maxval) || w == 0 || h == 0)
    throw Error(path, "PGM header: invalid width, height or maxval");
  if (maxval != 255) throw Error(path, "PGM maxval " + ms + ": only 255 (8-bit) is read");
  if (p == end) throw Error(path, "PGM image has no pixel data");
  ++p;  // the single whitespace after maxval
  if (w > static_cast<std::uint64_t>(end - p) / h)
    throw Error(path, "file truncated: " + ws + " x " + hs + " pixels but " +
                          std::to_string(end - p) + " bytes of data");
  width = static_cast<std::size_t>(w);
  height = static_cast<std::size_t>(h);
  return std::vector<std::uint8_t>(p, p + width * height);
}

}  // namespace detail

/// Reads a map YAML and its PGM image into a grid (trinary: p = (255 - pixel) / 255, or pixel /
/// 255 with negate 1, against the YAML's thresholds). Throws io::Error naming the file.
inline OccupancyGrid2D read_ros_map(const std::string& yaml_path) {
  const detail::FileBuffer buf = detail::read_file(yaml_path);
  std::string image, key, value;
  double occupied_thresh = -1, free_thresh = -1;
  int negate = 0;
  OccupancyGrid2D grid;
  bool have_res = false, have_origin = false;
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    if (!detail::yaml_entry(b, e, key, value)) return;
    const auto bad = [&] {
      return Error(yaml_path,
                   "line " + std::to_string(line) + ": invalid " + key + " '" + value + "'");
    };
    const auto number = [&](const std::string& text, double& out) {
      if (!detail::parse_real_token(text.data(), text.data() + text.size(), out)) throw bad();
    };
    if (key == "image") {
      if (!detail::yaml_scalar(value.data(), value.data() + value.size(), image)) throw bad();
    } else if (key == "resolution") {
      number(value, grid.resolution);
      have_res = grid.resolution > 0;
      if (!have_res) throw bad();
    } else if (key == "origin") {
      double xyz[3];
      if (value.size() < 2 || value.front() != '[' || value.back() != ']') throw bad();
      std::string list = value.substr(1, value.size() - 2);
      for (char& c : list) c = c == ',' ? ' ' : c;
      if (detail::scan_line_numbers(yaml_path, line, list.data(), list.data() + list.size(), xyz, 3,
                                    false) != 3)
        throw bad();
      grid.origin[0] = xyz[0];
      grid.origin[1] = xyz[1];
      have_origin = true;
    } else if (key == "occupied_thresh") {
      number(value, occupied_thresh);
    } else if (key == "free_thresh") {
      number(value, free_thresh);
    } else if (key == "negate") {
      if (value != "0" && value != "1") throw bad();
      negate = value == "1";
    }
  });
  if (image.empty() || !have_res || !have_origin || occupied_thresh < 0 || free_thresh < 0)
    throw Error(yaml_path, "needs image, resolution, origin, occupied_thresh and free_thresh");
  const std::filesystem::path image_path =
      std::filesystem::path(yaml_path).parent_path() / std::filesystem::path(image);
  const std::vector<std::uint8_t> pixels =
      detail::read_pgm(image_path.string(), grid.width, grid.height);
  grid.cells.resize(pixels.size());
  for (std::size_t row = 0; row < grid.height; ++row) {
    for (std::size_t x = 0; x < grid.width; ++x) {
      const double shade = pixels[row * grid.width + x] / 255.0;
      const double p = negate ? shade : 1.0 - shade;
      grid.cells[x + (grid.height - 1 - row) * grid.width] =
          p > occupied_thresh ? OccupancyGrid2D::kOccupied
          : p < free_thresh   ? OccupancyGrid2D::kFree
                              : OccupancyGrid2D::kUnknown;
    }
  }
  return grid;
}

}  // namespace knnocc::io
