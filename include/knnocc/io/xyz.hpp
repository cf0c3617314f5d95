#pragma once
// ASCII "x y z" point files (.xyz, and OctoMap's .dat scan files, which are the same thing).
//
// One point per line; columns after the third are ignored (they may be anything, e.g. colours).
// Blank lines and lines whose first non-blank character is '#' are skipped. A line with fewer
// than three numbers, or an unparsable number among the first three, throws io::Error with the
// line number. NaN/Inf values are returned as read; the mapping layer skips and counts them.

#include <string>

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

}  // namespace knnocc::io
