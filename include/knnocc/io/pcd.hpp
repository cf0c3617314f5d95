// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PCL's PCD point clouds (v0.7 and the older v0.6/v0.5 headers): read_pcd() and write_pcd().
//
// Reading supports DATA ascii, binary and binary_compressed (LZF, fields stored one after
// another: all x, then all y, ...). Fields x, y, z must be float scalars (TYPE F, SIZE 4 or 8,
// COUNT 1); an integer scalar field "id" fills Cloud::ids; a field "rgb" or "rgba" (SIZE 4,
// COUNT 1, TYPE F, U or I: PCL's packed 0x00RRGGBB / 0xAARRGGBB, alpha ignored; in ascii files
// an integer or the float whose bits hold the colour) fills Cloud::colors; every other field
// (intensity, normals, descriptors with COUNT > 1, "_" padding) is skipped. WIDTH x HEIGHT must
// equal POINTS; organised clouds (HEIGHT > 1) are read row by row. VIEWPOINT (tx ty tz qw qx qy qz)
// is returned in PcdInfo, points are returned as stored.
//
// NaN/Inf coordinates are returned as read (the mapping layer skips and counts them). Every
// problem with the file (bad header, unknown types, wrong counts, truncated data, a corrupt or
// lying LZF block) throws io::Error naming the file; POINTS and the declared uncompressed size
// are checked against the bytes present before anything is allocated. A binary_compressed
// block is checked whole (io/detail/lzf.hpp: lzf_check) before the cloud is allocated, then
// decoded piece by piece straight into it: peak memory is the file plus the cloud.
//
// Writing produces "FIELDS x y z" (+ "id" as U 4) as ascii, binary or binary_compressed,
// atomically (temp file + rename).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "atomic_file.hpp"
#include "cloud.hpp"
#include "detail/bytes.hpp"
#include "detail/file_text.hpp"
#include "detail/lzf.hpp"
#include "error.hpp"

namespace knnocc::io {

enum class PcdData { ascii, binary, binary_compressed };

struct PcdInfo {
  std::vector<std::string> fields;
  std::uint64_t width = 0, height = 0, points = 0;
  PcdData data = PcdData::ascii;
  double viewpoint[7] = {0, 0, 0, 1, 0, 0, 0};  ///< tx ty tz qw qx qy qz (sensor pose)
};

namespace detail {

struct PcdField {
  std::string name;
  char type = 'F';              // F, I or U
  std::size_t size = 4;         // bytes per value
  std::size_t count = 1;        // values per point
  std::size_t offset = 0;       // byte offset in a binary record
  std::size_t first_token = 0;  // index of its first value on an ascii line
};

struct PcdHeader {
  PcdInfo info;
  std::vector<PcdField> fields;
  std::size_t record_size = 0;  // bytes per point
  std::size_t tokens = 0;       // values per point
  std::size_t data_offset = 0;
  std::size_t line_count = 0;
  int x = -1, y = -1, z = -1, id = -1, rgb = -1;
};

inline PcdHeader parse_pcd_header(const std::string& path, const char* data, std::size_t size) {
  PcdHeader h;
  const char* p = data;
  const char* const end = data + size;
  std::vector<std::string> sizes, types, counts;
  bool have_fields = false, have_width = false, have_height = false, have_points = false,
       have_data = false;
  std::size_t line = 0;
  while (!have_data) {
    if (p == end) {
      throw Error(path, line == 0 ? std::string("empty file, not a PCD file")
                                  : "PCD header has no DATA line");
    }
    ++line;
    const void* nl = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
    const char* le = nl ? static_cast<const char*>(nl) : end;
    check_header_length(path, "PCD", static_cast<std::size_t>(le - data));
    std::vector<std::string> w = split_words(p, le);
    p = nl ? le + 1 : end;
    const auto bad = [&](const std::string& why) {
      return Error(path, "PCD header line " + std::to_string(line) + ": " + why);
    };
    if (w.empty() || w[0][0] == '#') continue;
    const std::string key = w[0];
    w.erase(w.begin());
    auto one_number = [&](std::uint64_t& out) {
      if (w.size() != 1 || !parse_int_token(w[0].data(), w[0].data() + w[0].size(), out)) {
        throw bad("expected one non-negative integer after " + key);
      }
    };
    if (key == "VERSION") {
      continue;
    } else if (key == "FIELDS" || key == "COLUMNS") {
      if (w.empty()) throw bad("FIELDS names no field");
      h.info.fields = w;
      have_fields = true;
    } else if (key == "SIZE") {
      sizes = w;
    } else if (key == "TYPE") {
      types = w;
    } else if (key == "COUNT") {
      counts = w;
    } else if (key == "WIDTH") {
      one_number(h.info.width);
      have_width = true;
    } else if (key == "HEIGHT") {
      one_number(h.info.height);
      have_height = true;
    } else if (key == "POINTS") {
      one_number(h.info.points);
      have_points = true;
    } else if (key == "VIEWPOINT") {
      if (w.size() != 7) throw bad("VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
      for (int i = 0; i < 7; ++i) {
        const std::string& s = w[static_cast<std::size_t>(i)];
        if (!parse_real_token(s.data(), s.data() + s.size(), h.info.viewpoint[i]) ||
            !std::isfinite(h.info.viewpoint[i])) {
          throw bad("invalid VIEWPOINT number '" + s + "'");
        }
      }
    } else if (key == "DATA") {
      if (w.size() != 1) throw bad("expected DATA ascii, binary or binary_compressed");
      if (w[0] == "ascii") {
        h.info.data = PcdData::ascii;
      } else if (w[0] == "binary") {
        h.info.data = PcdData::binary;
      } else if (w[0] == "binary_compressed") {
        h.info.data = PcdData::binary_compressed;
      } else {
        throw bad("unknown DATA type '" + w[0] + "'");
      }
      have_data = true;
    } else {
      throw bad(line == 1 ? "not a PCD file (unknown header keyword '" + key + "')"
                          : "unknown PCD header keyword '" + key + "'");
    }
  }
  h.data_offset = static_cast<std::size_t>(p - data);
  h.line_count = line;
  if (!have_fields) throw Error(path, "PCD header has no FIELDS line");
  const std::size_t n = h.info.fields.size();
  if (sizes.size() != n || types.size() != n) {
    throw Error(path, "PCD header: FIELDS names " + std::to_string(n) + " fields but SIZE has " +
                          std::to_string(sizes.size()) + " and TYPE " +
                          std::to_string(types.size()) + " entries");
  }
  if (!counts.empty() && counts.size() != n) {
    throw Error(path, "PCD header: FIELDS names " + std::to_string(n) + " fields but COUNT has " +
                          std::to_string(counts.size()) + " entries");
  }
  if (!have_width || !have_height) throw Error(path, "PCD header needs WIDTH and HEIGHT");
  const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max();
  if (h.info.height != 0 && h.info.width > limit / h.info.height) {
    throw Error(path, "PCD header: WIDTH x HEIGHT overflows");
  }
  if (!have_points) h.info.points = h.info.width * h.info.height;
  if (h.info.width * h.info.height != h.info.points) {
    throw Error(path, "PCD header: WIDTH " + std::to_string(h.info.width) + " x HEIGHT " +
                          std::to_string(h.info.height) + " != POINTS " +
                          std::to_string(h.info.points));
  }
  std::unordered_set<std::string> names;  // duplicates found in linear time
  h.fields.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    PcdField f;
    f.name = h.info.fields[i];
    const std::string where = "PCD field '" + f.name + "': ";
    if (types[i].size() != 1 || (types[i][0] != 'F' && types[i][0] != 'I' && types[i][0] != 'U')) {
      throw Error(path, where + "unknown TYPE '" + types[i] + "' (expected F, I or U)");
    }
    f.type = types[i][0];
    if (!parse_int_token(sizes[i].data(), sizes[i].data() + sizes[i].size(), f.size) ||
        !(f.size == 1 || f.size == 2 || f.size == 4 || f.size == 8) ||
        (f.type == 'F' && f.size < 4)) {
      throw Error(path, where + "invalid SIZE '" + sizes[i] + "' for TYPE " + f.type);
    }
    if (!counts.empty() &&
        (!parse_int_token(counts[i].data(), counts[i].data() + counts[i].size(), f.count) ||
         f.count == 0 || f.count > (std::size_t{1} << 20))) {
      throw Error(path, where + "invalid COUNT '" + counts[i] + "'");
    }
    f.offset = h.record_size;
    f.first_token = h.tokens;
    h.record_size += f.size * f.count;
    h.tokens += f.count;
    if (f.name != "_" && !names.insert(f.name).second)
      throw Error(path, "PCD header: duplicate field " + f.name);
    const int idx = static_cast<int>(i);
    if (f.name == "x") h.x = idx;
    if (f.name == "y") h.y = idx;
    if (f.name == "z") h.z = idx;
    if (f.name == "id") h.id = idx;
    if ((f.name == "rgb" || f.name == "rgba") && h.rgb < 0 && f.size == 4 && f.count == 1)
      h.rgb = idx;
    h.fields.push_back(f);
  }
  for (const int* slot : {&h.x, &h.y, &h.z}) {
    const char* name = slot == &h.x ? "x" : slot == &h.y ? "y" : "z";
    if (*slot < 0) throw Error(path, std::string("PCD file has no field '") + name + "'");
    const PcdField& f = h.fields[static_cast<std::size_t>(*slot)];
    if (f.type != 'F' || f.count != 1) {
      throw Error(path, std::string("PCD field '") + name + "' must be a float scalar (TYPE F)");
    }
  }
  if (h.id >= 0) {
    const PcdField& f = h.fields[static_cast<std::size_t>(h.id)];
    if (f.type == 'F' || f.count != 1) {
      throw Error(path, "PCD field 'id' must be an integer scalar (TYPE I or U)");
    }
  }
  return h;
}

inline float pcd_coord(const unsigned char* p, const PcdField& f) {
  return f.size == 4 ? load_le<float>(p) : to_float(load_le<double>(p));
}

inline std::int64_t pcd_integer(const unsigned char* p, const PcdField& f) {
  const bool s = f.type == 'I';
  switch (f.size) {
    case 1:
      return s ? load_le<std::int8_t>(p) : load_le<std::uint8_t>(p);
    case 2:
      return s ? load_le<std::int16_t>(p) : load_le<std::uint16_t>(p);
    case 4:
      return s ? load_le<std::int32_t>(p) : load_le<std::uint32_t>(p);
    default: {
      const std::uint64_t u = load_le<std::uint64_t>(p);
      if (!s && u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return -1;
      return static_cast<std::int64_t>(u);
    }
  }
}

// PCL's packed colour: the 4 bytes of an rgb/rgba value as 0x(AA)RRGGBB.
inline Rgb pcd_color(std::uint32_t packed) {
  return Rgb{static_cast<std::uint8_t>(packed >> 16), static_cast<std::uint8_t>(packed >> 8),
             static_cast<std::uint8_t>(packed)};
}

// Points from binary data where value j of point i lies at base[f] + i * stride[f]; the slots
// are x, y, z, id, rgb.
inline Cloud pcd_gather(const std::string& path, const PcdHeader& h, std::size_t n,
                        const unsigned char* const base[5], const std::size_t stride[5]) {
  Cloud cloud;
  cloud.points.resize(n);
  const PcdField& fx = h.fields[static_cast<std::size_t>(h.x)];
  const PcdField& fy = h.fields[static_cast<std::size_t>(h.y)];
  const PcdField& fz = h.fields[static_cast<std::size_t>(h.z)];
  for (std::size_t i = 0; i < n; ++i) {
    cloud.points[i] =
        Point3f{pcd_coord(base[0] + i * stride[0], fx), pcd_coord(base[1] + i * stride[1], fy),
                pcd_coord(base[2] + i * stride[2], fz)};
  }
  cloud.ids_declared = h.id >= 0;
  if (h.id >= 0) {
    const PcdField& fi = h.fields[static_cast<std::size_t>(h.id)];
    cloud.ids.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t id = pcd_integer(base[3] + i * stride[3], fi);
      if (id < 0) throw Error(path, "point " + std::to_string(i) + " has a negative or huge id");
      cloud.ids[i] = static_cast<std::uint64_t>(id);
    }
  }
  if (h.rgb >= 0) {
    cloud.colors.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      cloud.colors[i] = pcd_color(load_le<std::uint32_t>(base[4] + i * stride[4]));
  }
  return cloud;
}

// binary_compressed data holds the fields one after another (field f's values from byte
// n * offset_f, one per point, size * count bytes apart). PcdFieldBlocks fills a cloud from
// consecutive pieces of that data, in order: a value split between two pieces is carried over.
struct PcdFieldBlocks {
  PcdFieldBlocks(const std::string& file, const PcdHeader& h, std::size_t n) : path(file) {
    cloud.points.resize(n);
    cloud.ids_declared = h.id >= 0;
    if (h.id >= 0) cloud.ids.resize(n);
    if (h.rgb >= 0) cloud.colors.resize(n);
    const int slots[5] = {h.x, h.y, h.z, h.id, h.rgb};
    for (int k = 0; k < 5; ++k) {
      if (slots[k] < 0) continue;
      Block& b = blocks[used++];
      b.slot = k;
      b.field = &h.fields[static_cast<std::size_t>(slots[k])];
      b.begin = std::uint64_t{n} * b.field->offset;
      b.stride = b.field->size * b.field->count;
      b.end = b.begin + std::uint64_t{n} * b.stride;
    }
  }

  // Bytes [offset, offset + size) of the decoded data.
  void take(std::uint64_t offset, const unsigned char* data, std::size_t size) {
    const std::uint64_t stop = offset + size;
    for (int k = 0; k < used; ++k) {
      Block& b = blocks[k];
      std::uint64_t at = std::max(offset, b.begin);
      const std::uint64_t last = std::min(stop, b.end);
      const std::size_t value = b.field->size;
      while (at < last) {
        const std::uint64_t i = (at - b.begin) / b.stride;
        const std::size_t within = static_cast<std::size_t>((at - b.begin) % b.stride);
        if (within >= value) {  // the point's further values (COUNT > 1): not read
          at += b.stride - within;
          continue;
        }
        if (within == 0 && at + value <= last) {  // whole values in this piece
          for (std::uint64_t j = i; at + value <= last; at += b.stride, ++j) {
            store(b, static_cast<std::size_t>(j), data + (at - offset));
          }
          continue;
        }
        const std::size_t part =
            static_cast<std::size_t>(std::min<std::uint64_t>(value - within, last - at));
        std::memcpy(b.carry + within, data + (at - offset), part);
        at += part;
        if (within + part == value) store(b, static_cast<std::size_t>(i), b.carry);
      }
    }
  }

  std::string path;
  Cloud cloud;

 private:
  struct Block {
    int slot = 0;  // 0-2: x, y, z; 3: id; 4: rgb
    const PcdField* field = nullptr;
    std::uint64_t begin = 0, end = 0;
    std::size_t stride = 0;
    unsigned char carry[8] = {};  // a value split between two pieces
  };

  void store(const Block& b, std::size_t i, const unsigned char* p) {
    if (b.slot < 3) {
      const float v = pcd_coord(p, *b.field);
      (b.slot == 0 ? cloud.points[i].x : b.slot == 1 ? cloud.points[i].y : cloud.points[i].z) = v;
      return;
    }
    if (b.slot == 4) {
      cloud.colors[i] = pcd_color(load_le<std::uint32_t>(p));
      return;
    }
    const std::int64_t id = pcd_integer(p, *b.field);
    if (id < 0) throw Error(path, "point " + std::to_string(i) + " has a negative or huge id");
    cloud.ids[i] = static_cast<std::uint64_t>(id);
  }

  Block blocks[5];
  int used = 0;
};

inline Cloud read_pcd_binary(const std::string& path, const PcdHeader& h, const unsigned char* p,
                             std::size_t remaining) {
  const std::uint64_t points = h.info.points;
  const std::size_t rec = h.record_size;
  const int slots[5] = {h.x, h.y, h.z, h.id < 0 ? h.x : h.id, h.rgb < 0 ? h.x : h.rgb};
  const unsigned char* base[5];
  std::size_t stride[5];
  if (h.info.data == PcdData::binary) {
    if (points > remaining / rec) {
      throw Error(path, "file truncated: POINTS " + std::to_string(points) + " x " +
                            std::to_string(rec) + " bytes but only " + std::to_string(remaining) +
                            " bytes of data");
    }
    for (int k = 0; k < 5; ++k) {
      base[k] = p + h.fields[static_cast<std::size_t>(slots[k])].offset;
      stride[k] = rec;
    }
    return pcd_gather(path, h, static_cast<std::size_t>(points), base, stride);
  }
  // binary_compressed: uint32 compressed size, uint32 uncompressed size, LZF data.
  if (remaining < 8) throw Error(path, "file truncated: no compressed-data sizes after DATA");
  const std::uint32_t packed = load_le<std::uint32_t>(p);
  const std::uint32_t raw = load_le<std::uint32_t>(p + 4);
  if (packed > remaining - 8) {
    throw Error(path, "file truncated: compressed block of " + std::to_string(packed) +
                          " bytes but only " + std::to_string(remaining - 8) + " bytes follow");
  }
  if (points > std::numeric_limits<std::uint32_t>::max() / rec || points * rec != raw) {
    throw Error(path, "compressed block declares " + std::to_string(raw) + " bytes but POINTS " +
                          std::to_string(points) + " x " + std::to_string(rec) +
                          " bytes per point differ");
  }
  if (raw > std::size_t{packed} * kLzfMaxRatio) {
    throw Error(path, "compressed block of " + std::to_string(packed) +
                          " bytes cannot hold the declared " + std::to_string(raw) + " bytes");
  }
  // The stream is checked before anything is allocated for it, then decoded piece by piece
  // straight into the cloud: memory is the cloud, not the cloud plus the decoded fields.
  const std::string problem = lzf_check(p + 8, packed, raw);
  if (!problem.empty()) throw Error(path, "corrupt binary_compressed data: " + problem);
  const std::size_t n = static_cast<std::size_t>(points);
  PcdFieldBlocks blocks(path, h, n);
  LzfPieces pieces([&blocks](std::uint64_t offset, const unsigned char* data, std::size_t size) {
    blocks.take(offset, data, size);
  });
  lzf_decode(p + 8, packed, raw, pieces);
  pieces.finish();
  return std::move(blocks.cloud);
}

// An ascii rgb/rgba value: PCL writes the packed colour as an unsigned integer (since 1.8), older
// writers the float whose bits hold it.
inline std::optional<std::uint32_t> pcd_ascii_color(const char* b, const char* e) {
  std::uint64_t u = 0;
  if (parse_int_token(b, e, u)) {
    if (u > 0xFFFFFFFFull) return std::nullopt;
    return static_cast<std::uint32_t>(u);
  }
  float f = 0.0f;
  if (!parse_real_token(b, e, f)) return std::nullopt;
  std::uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

inline Cloud read_pcd_ascii(const std::string& path, const PcdHeader& h, const char* p,
                            const char* end) {
  const std::uint64_t points = h.info.points;
  // Every value needs at least one character and one separator.
  if (points > static_cast<std::uint64_t>(end - p + 1) / (2 * h.tokens)) {
    throw Error(path, "file truncated: POINTS " + std::to_string(points) + " but only " +
                          std::to_string(end - p) + " bytes of ascii data");
  }
  const std::size_t n = static_cast<std::size_t>(points);
  Cloud cloud;
  cloud.points.resize(n);
  cloud.ids_declared = h.id >= 0;
  if (h.id >= 0) cloud.ids.resize(n);
  if (h.rgb >= 0) cloud.colors.resize(n);
  const std::size_t tx = h.fields[static_cast<std::size_t>(h.x)].first_token;
  const std::size_t ty = h.fields[static_cast<std::size_t>(h.y)].first_token;
  const std::size_t tz = h.fields[static_cast<std::size_t>(h.z)].first_token;
  const std::size_t tid = h.id >= 0 ? h.fields[static_cast<std::size_t>(h.id)].first_token : 0;
  const std::size_t trgb =
      h.rgb >= 0 ? h.fields[static_cast<std::size_t>(h.rgb)].first_token : ~std::size_t{0};
  std::size_t i = 0;
  for_each_line(p, end, [&](std::size_t line, const char* b, const char* e) {
    const std::string at = "line " + std::to_string(line + h.line_count) + ": ";
    std::size_t t = 0;
    float xyz[3] = {0, 0, 0};
    while (true) {
      while (b != e && is_blank(*b)) ++b;
      if (b == e) break;
      const char* te = b;
      while (te != e && !is_blank(*te)) ++te;
      if (t == tx || t == ty || t == tz) {
        if (!parse_real_token(b, te, xyz[t == tx ? 0 : t == ty ? 1 : 2])) {
          throw Error(path, at + "cannot parse " + quote_token(b, te) + " as a number");
        }
      } else if (h.id >= 0 && t == tid) {
        std::int64_t id = 0;
        if (!parse_int_token(b, te, id) || id < 0) {
          throw Error(path, at + "invalid id " + quote_token(b, te));
        }
        if (i < n) cloud.ids[i] = static_cast<std::uint64_t>(id);
      } else if (t == trgb) {
        const auto packed = pcd_ascii_color(b, te);
        if (!packed) throw Error(path, at + "invalid colour " + quote_token(b, te));
        if (i < n) cloud.colors[i] = pcd_color(*packed);
      }
      ++t;
      b = te;
    }
    if (t == 0) return;  // blank line
    if (t != h.tokens) {
      throw Error(path, at + "expected " + std::to_string(h.tokens) + " values, found " +
                            std::to_string(t));
    }
    if (i == n) throw Error(path, at + "more data lines than POINTS " + std::to_string(n));
    cloud.points[i++] = Point3f{xyz[0], xyz[1], xyz[2]};
  });
  if (i != n) {
    throw Error(path, "file truncated: POINTS " + std::to_string(n) + " but " + std::to_string(i) +
                          " data lines");
  }
  return cloud;
}

}  // namespace detail

/// Reads the points (and "id" values) of a PCD file; `info`, when given, gets its header.
inline Cloud read_pcd(const std::string& path, PcdInfo* info = nullptr) {
  const detail::FileBuffer buf = detail::read_file(path);
  const detail::PcdHeader h = detail::parse_pcd_header(path, buf.data(), buf.size());
  if (info) *info = h.info;
  if (h.info.data == PcdData::ascii) {
    return detail::read_pcd_ascii(path, h, buf.data() + h.data_offset, buf.end());
  }
  return detail::read_pcd_binary(path, h,
                                 reinterpret_cast<const unsigned char*>(buf.data()) + h.data_offset,
                                 buf.size() - h.data_offset);
}

/// Writes "x y z" floats (+ "id" as U 4 when ids is given; each must fit 32 bits).
inline void write_pcd(const std::string& path, const std::vector<Point3f>& pts,
                      const std::vector<std::uint64_t>* ids = nullptr,
                      PcdData data = PcdData::binary) {
  if (ids && ids->size() != pts.size()) {
    throw Error(path, "write_pcd: " + std::to_string(ids->size()) + " ids for " +
                          std::to_string(pts.size()) + " points");
  }
  if (ids) {
    for (std::uint64_t id : *ids) {
      if (id > 0xFFFFFFFFull)
        throw Error(path, "write_pcd: id " + std::to_string(id) + " > 2^32-1");
    }
  }
  const std::string n = std::to_string(pts.size());
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  out += ids ? "FIELDS x y z id\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
             : "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  out += "WIDTH " + n + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + n + "\nDATA ";
  out += data == PcdData::ascii    ? "ascii\n"
         : data == PcdData::binary ? "binary\n"
                                   : "binary_compressed\n";
  const std::size_t fields = ids ? 4 : 3;
  if (data == PcdData::ascii) {
    char line[256];
    for (std::size_t i = 0; i < pts.size(); ++i) {
      char* w = line;
      char* const lim = line + sizeof line;
      w = detail::format_float_roundtrip(w, lim, pts[i].x);
      *w++ = ' ';
      w = detail::format_float_roundtrip(w, lim, pts[i].y);
      *w++ = ' ';
      w = detail::format_float_roundtrip(w, lim, pts[i].z);
      if (ids) {
        *w++ = ' ';
        w = std::to_chars(w, lim, (*ids)[i]).ptr;
      }
      *w++ = '\n';
      out.append(line, w);
    }
  } else {
    // binary: one record per point; binary_compressed: one block per field, then LZF.
    std::vector<char> raw(pts.size() * fields * 4);
    const bool soa = data == PcdData::binary_compressed;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const float v[3] = {pts[i].x, pts[i].y, pts[i].z};
      for (std::size_t f = 0; f < fields; ++f) {
        char* at = raw.data() + 4 * (soa ? f * pts.size() + i : i * fields + f);
        if (f < 3) {
          detail::store_le(at, v[f]);
        } else {
          detail::store_le(at, static_cast<std::uint32_t>((*ids)[i]));
        }
      }
    }
    if (!soa) {
      out.append(raw.data(), raw.size());
    } else {
      const auto packed =
          detail::lzf_compress(reinterpret_cast<const unsigned char*>(raw.data()), raw.size());
      if (raw.size() > 0xFFFFFFFFull || packed.size() > 0xFFFFFFFFull) {
        throw Error(path, "write_pcd: cloud too large for binary_compressed (4 GB limit)");
      }
      char sizes[8];
      detail::store_le(sizes, static_cast<std::uint32_t>(packed.size()));
      detail::store_le(sizes + 4, static_cast<std::uint32_t>(raw.size()));
      out.append(sizes, 8);
      out.append(reinterpret_cast<const char*>(packed.data()), packed.size());
    }
  }
  AtomicFile file(path);
  file.write(out);
  file.commit();
}

}  // namespace knnocc::io
