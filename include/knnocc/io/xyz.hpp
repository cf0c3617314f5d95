// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ASCII "x y z" point files (.xyz, and OctoMap's .dat scan files, which are the same thing).
//
// One point per line; columns after the third are ignored (they may be anything, e.g. colours).
// Blank lines and lines whose first non-blank character is '#' are skipped. A line with fewer
// than three numbers, or an unparsable number among the first three, throws io::Error with the
// line number. NaN/Inf values are returned as read; the mapping layer skips and counts them.
// write_xyz() writes "x y z" lines with the shortest text that reads back to the same floats.

#include <string>
#include <vector>

#include "cloud.hpp"
#include "detail/file_text.hpp"
#include "error.hpp"

namespace knnocc::io {

inline Cloud read_xyz(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  Cloud cloud;
  // Lines are rarely shorter than ~20 bytes; a rough reserve avoids most regrowth copies.
  cloud.points.reserve(buf.size() / 20 + 1);
  detail::for_each_line(buf.data(), buf.end(), [&](std::size_t line, const char* b, const char* e) {
    while (b != e && detail::is_blank(*b)) ++b;
    if (b == e || *b == '#') return;
    float v[3];
    const std::size_t n = detail::scan_line_numbers(path, line, b, e, v, 3, false);
    if (n < 3) {
      throw Error(path, "line " + std::to_string(line) + ": expected 3 numbers (x y z), found " +
                            std::to_string(n));
    }
    cloud.points.push_back(Point3f{v[0], v[1], v[2]});
  });
  return cloud;
}

inline void write_xyz(const std::string& path, const std::vector<Point3f>& pts) {
  AtomicFile out(path);
  std::vector<char> chunk(1 << 16);
  char* w = chunk.data();
  char* const lim = chunk.data() + chunk.size();
  for (const Point3f& p : pts) {
    if (lim - w < 200) {  // room for one full line
      out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
      w = chunk.data();
    }
    w = detail::format_float_roundtrip(w, lim, p.x);
    *w++ = ' ';
    w = detail::format_float_roundtrip(w, lim, p.y);
    *w++ = ' ';
    w = detail::format_float_roundtrip(w, lim, p.z);
    *w++ = '\n';
  }
  out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
  out.commit();
}

}  // namespace knnocc::io
