// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// PLY point clouds: read_ply() and write_ply().
//
// Reading supports "format ascii 1.0", "binary_little_endian 1.0" and "binary_big_endian 1.0".
// The "vertex" element must have scalar properties x, y, z of type float/float32/double/float64
// (doubles are narrowed to float); an optional integer property "id" fills Cloud::ids; scalar
// properties "red", "green" and "blue", all three, fill Cloud::colors, each channel scaled from
// its type to 0..255 (ply_colour_channel below): uchar as is; ushort (16-bit colour, as PDAL and
// LAS write it) times 255/65535, rounded; every other integer type (char, short, int, uint) as is
// on the 0..255 scale; float and double on the 0..1 scale, times 255, rounded. Values beyond the
// scale clamp to 0 or 255 (negative values, NaN: 0). In ascii files a token that is no value of
// its declared type (a uchar 256, a fraction for an int) is an error. The optional integer
// properties "found", "visible" and "observations" (a SLAM
// system's counters for the map point, core/point_evidence.hpp) fill Cloud::evidence. Any other
// vertex property of a PLY scalar type is skipped. Other elements (e.g. "face" with list
// properties) are skipped when they follow "vertex"; in binary files an element with a list
// property *before* "vertex" is rejected, since skipping it would need a per-record walk.
// comment/obj_info header lines are ignored and CRLF line ends are tolerated in the header.
//
// NaN and Inf coordinates are NOT an error here: they are returned as read, and the mapping layer
// skips and counts them. Every problem with the file itself (cannot open, not a PLY, unknown
// format, missing x/y/z, truncated or unparsable data, vertex counts larger than the file can
// hold) throws io::Error naming the file; nothing is allocated beyond what the file can back.
//
// Writing produces binary little-endian (or ascii) "float x y z" plus "uint id" when ids are
// given, atomically: a temp file in the same directory is renamed over the target.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <unordered_set>
#include <vector>

#include "cloud.hpp"
#include "detail/bytes.hpp"
#include "detail/file_text.hpp"
#include "detail/ply_header.hpp"
#include "error.hpp"

namespace knnocc::io {
namespace detail {

inline float load_coord(const unsigned char* p, PlyType t, bool swap) noexcept {
  return t == PlyType::f32 ? load_scalar<float>(p, swap) : to_float(load_scalar<double>(p, swap));
}

// Integer property as int64 (every PLY integer type fits).
inline std::int64_t load_integer(const unsigned char* p, PlyType t, bool swap) noexcept {
  switch (t) {
    case PlyType::i8:
      return load_scalar<std::int8_t>(p, swap);
    case PlyType::u8:
      return load_scalar<std::uint8_t>(p, swap);
    case PlyType::i16:
      return load_scalar<std::int16_t>(p, swap);
    case PlyType::u16:
      return load_scalar<std::uint16_t>(p, swap);
    case PlyType::i32:
      return load_scalar<std::int32_t>(p, swap);
    case PlyType::u32:
      return load_scalar<std::uint32_t>(p, swap);
    case PlyType::f32:
    case PlyType::f64:
      break;
  }
  return 0;
}

struct PlyVertexLayout {
  std::size_t index = 0;  // position of "vertex" in the element list
  int x = -1, y = -1, z = -1, id = -1;
  int rgb[3] = {-1, -1, -1};  // red, green, blue: all three scalars, or all -1

  bool has_color() const { return rgb[0] >= 0; }
  int color_channel(int slot) const {  // 0-2 when `slot` is a colour property, else -1
    for (int c = 0; c < 3; ++c)
      if (has_color() && rgb[c] == slot) return c;
    return -1;
  }
  int evidence[3] = {-1, -1, -1};  // found, visible, observations
  bool has_evidence() const { return evidence[0] >= 0 || evidence[1] >= 0 || evidence[2] >= 0; }
};

// The vertex's red, green and blue scalar properties, when it has all three.
inline void locate_colour(const PlyElement& el, PlyVertexLayout& v) {
  const char* const names[3] = {"red", "green", "blue"};
  int slots[3];
  for (int c = 0; c < 3; ++c) {
    slots[c] = el.find(names[c]);
    if (slots[c] < 0) return;
    if (el.props[static_cast<std::size_t>(slots[c])].is_list) return;
  }
  for (int c = 0; c < 3; ++c) v.rgb[c] = slots[c];
}

// An integer colour channel on 0..255: ushort on the 16-bit scale, other integer types as is.
inline std::uint8_t colour_from_integer(std::int64_t v, PlyType t) noexcept {
  if (t == PlyType::u16) return static_cast<std::uint8_t>((v * 255 + 32767) / 65535);
  return static_cast<std::uint8_t>(v <= 0 ? 0 : v >= 255 ? 255 : v);
}
// A float or double colour channel on 0..1 (NaN and below 0: 0; above 1: 255).
inline std::uint8_t colour_from_real(double v) noexcept {
  if (!(v > 0.0)) return 0;
  if (v >= 1.0) return 255;
  return static_cast<std::uint8_t>(v * 255.0 + 0.5);
}

// Whether an ascii integer token fits its declared type.
inline bool ply_integer_fits(std::int64_t v, PlyType t) noexcept {
  switch (t) {
    case PlyType::i8:
      return v >= -128 && v <= 127;
    case PlyType::u8:
      return v >= 0 && v <= 255;
    case PlyType::i16:
      return v >= -32768 && v <= 32767;
    case PlyType::u16:
      return v >= 0 && v <= 65535;
    case PlyType::i32:
      return v >= -2147483648ll && v <= 2147483647ll;
    case PlyType::u32:
      return v >= 0 && v <= 4294967295ll;
    case PlyType::f32:
    case PlyType::f64:
      break;
  }
  return true;
}

// One binary colour channel of type t at p, on 0..255.
inline std::uint8_t load_colour(const unsigned char* p, PlyType t, bool swap) noexcept {
  if (t == PlyType::u8) return *p;
  if (t == PlyType::f32) return colour_from_real(load_scalar<float>(p, swap));
  if (t == PlyType::f64) return colour_from_real(load_scalar<double>(p, swap));
  return colour_from_integer(load_integer(p, t, swap), t);
}

// The vertex properties of PointEvidence, in PlyVertexLayout::evidence's order.
inline const char* const kEvidenceNames[3] = {"found", "visible", "observations"};

// A SLAM counter as read (an integer in [0, 2^32 - 1]).
inline std::uint32_t evidence_value(const std::string& path, std::uint64_t vertex, int which,
                                    std::int64_t value) {
  if (value < 0 || value > 0xFFFFFFFFll)
    throw Error(path, "vertex " + std::to_string(vertex) + " has " + kEvidenceNames[which] + " " +
                          std::to_string(value) + " (must be in [0, 2^32 - 1])");
  return static_cast<std::uint32_t>(value);
}
inline void set_evidence(PointEvidence& e, int which, std::uint32_t value) {
  (which == 0 ? e.found : which == 1 ? e.visible : e.observations) = value;
}

inline PlyVertexLayout locate_vertex(const std::string& path, const PlyHeader& h) {
  PlyVertexLayout v;
  bool found = false;
  for (std::size_t i = 0; i < h.elements.size() && !found; ++i) {
    if (h.elements[i].name == "vertex") {
      v.index = i;
      found = true;
    }
  }
  if (!found) throw Error(path, "PLY file has no 'vertex' element");
  const PlyElement& el = h.elements[v.index];
  int* const slots[3] = {&v.x, &v.y, &v.z};
  const char* const names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    *slots[k] = el.find(names[k]);
    if (*slots[k] < 0) {
      throw Error(path, std::string("vertex element has no property '") + names[k] + "'");
    }
    const PlyProperty& prop = el.props[static_cast<std::size_t>(*slots[k])];
    if (prop.is_list || !ply_type_is_real(prop.type)) {
      throw Error(
          path, std::string("vertex property '") + names[k] + "' must be a float or double scalar");
    }
  }
  v.id = el.find("id");
  if (v.id >= 0) {
    const PlyProperty& prop = el.props[static_cast<std::size_t>(v.id)];
    if (prop.is_list || ply_type_is_real(prop.type)) {
      throw Error(path, "vertex property 'id' must be an integer scalar");
    }
  }
  locate_colour(el, v);
  for (int k = 0; k < 3; ++k) {
    v.evidence[k] = el.find(kEvidenceNames[k]);
    if (v.evidence[k] < 0) continue;
    const PlyProperty& prop = el.props[static_cast<std::size_t>(v.evidence[k])];
    if (prop.is_list || ply_type_is_real(prop.type))
      throw Error(path, std::string("vertex property '") + kEvidenceNames[k] +
                            "' must be an integer scalar");
  }
  return v;
}

inline Error ply_truncated(const std::string& path, std::uint64_t count, std::size_t bytes) {
  return Error(path, "file truncated: header claims " + std::to_string(count) +
                         " vertices but only " + std::to_string(bytes) + " bytes of data");
}

inline Cloud read_ply_binary(const std::string& path, const PlyHeader& h, const PlyVertexLayout& v,
                             const unsigned char* p, std::size_t remaining) {
  for (std::size_t i = 0; i < v.index; ++i) {
    const PlyElement& el = h.elements[i];
    if (const PlyProperty* list = el.first_list()) {
      throw Error(path, "unsupported binary PLY: element '" + el.name +
                            "' before 'vertex' has list property '" + list->name + "'");
    }
    const std::size_t rec = el.record_size();
    if (rec != 0 && el.count > remaining / rec) {
      throw Error(path, "file truncated: element '" + el.name + "' claims " +
                            std::to_string(el.count) + " records of " + std::to_string(rec) +
                            " bytes but only " + std::to_string(remaining) +
                            " bytes of data remain");
    }
    const std::size_t skip = static_cast<std::size_t>(el.count) * rec;
    p += skip;
    remaining -= skip;
  }

  const PlyElement& el = h.elements[v.index];
  if (const PlyProperty* list = el.first_list()) {
    throw Error(path,
                "unsupported binary PLY: list property '" + list->name + "' in the vertex element");
  }
  const std::size_t rec = el.record_size();
  // Checked before any allocation, so a lying header cannot make us reserve gigabytes.
  if (el.count > remaining / rec) throw ply_truncated(path, el.count, remaining);
  const std::size_t n = static_cast<std::size_t>(el.count);

  const bool swap = (h.format == PlyFormat::binary_le) != host_is_little_endian();
  const PlyProperty& px = el.props[static_cast<std::size_t>(v.x)];
  const PlyProperty& py = el.props[static_cast<std::size_t>(v.y)];
  const PlyProperty& pz = el.props[static_cast<std::size_t>(v.z)];

  Cloud cloud;
  cloud.points.resize(n);
  static_assert(sizeof(Point3f) == 3 * sizeof(float) && std::is_trivially_copyable_v<Point3f>,
                "the bulk memcpy below needs Point3f to be three packed floats");
  if (!swap && rec == sizeof(Point3f) && px.type == PlyType::f32 && py.type == PlyType::f32 &&
      pz.type == PlyType::f32 && px.offset == 0 && py.offset == 4 && pz.offset == 8) {
    // The common "float x y z" file is byte-identical to our array: one memcpy.
    if (n != 0) std::memcpy(cloud.points.data(), p, n * rec);
  } else {
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned char* r = p + i * rec;
      cloud.points[i] = Point3f{load_coord(r + px.offset, px.type, swap),
                                load_coord(r + py.offset, py.type, swap),
                                load_coord(r + pz.offset, pz.type, swap)};
    }
  }
  cloud.ids_declared = v.id >= 0;
  if (v.id >= 0) {
    const PlyProperty& pid = el.props[static_cast<std::size_t>(v.id)];
    cloud.ids.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::int64_t id = load_integer(p + i * rec + pid.offset, pid.type, swap);
      if (id < 0) {
        throw Error(path, "vertex " + std::to_string(i) + " has negative id " + std::to_string(id));
      }
      cloud.ids[i] = static_cast<std::uint64_t>(id);
    }
  }
  if (v.has_color()) {
    const PlyProperty* ch[3];
    for (int c = 0; c < 3; ++c) ch[c] = &el.props[static_cast<std::size_t>(v.rgb[c])];
    cloud.colors.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned char* r = p + i * rec;
      cloud.colors[i] = Rgb{load_colour(r + ch[0]->offset, ch[0]->type, swap),
                            load_colour(r + ch[1]->offset, ch[1]->type, swap),
                            load_colour(r + ch[2]->offset, ch[2]->type, swap)};
    }
  }
  if (v.has_evidence()) {
    cloud.evidence.resize(n);
    for (int k = 0; k < 3; ++k) {
      if (v.evidence[k] < 0) continue;
      const PlyProperty& prop = el.props[static_cast<std::size_t>(v.evidence[k])];
      for (std::size_t i = 0; i < n; ++i)
        set_evidence(
            cloud.evidence[i], k,
            evidence_value(path, i, k, load_integer(p + i * rec + prop.offset, prop.type, swap)));
    }
  }
  return cloud;
}

// Whitespace-separated tokens of an ascii PLY body, tracking the file line for error messages.
class PlyAsciiCursor {
 public:
  PlyAsciiCursor(const char* p, const char* end, std::size_t line)
      : p_(p), end_(end), line_(line) {}

  bool next(const char*& b, const char*& e) {
    while (p_ != end_ && is_space(*p_)) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
    if (p_ == end_) return false;
    b = p_;
    while (p_ != end_ && !is_space(*p_)) ++p_;
    e = p_;
    return true;
  }
  std::size_t line() const noexcept { return line_; }
  std::size_t remaining() const noexcept { return static_cast<std::size_t>(end_ - p_); }

 private:
  const char* p_;
  const char* end_;
  std::size_t line_;
};

inline Cloud read_ply_ascii(const std::string& path, const PlyHeader& h, const PlyVertexLayout& v,
                            const char* p, const char* end) {
  PlyAsciiCursor cur(p, end, h.line_count + 1);
  const char* b = nullptr;
  const char* e = nullptr;
  const auto where = [&](const PlyElement& el, std::uint64_t i) {
    return "line " + std::to_string(cur.line()) + " (" + el.name + " " + std::to_string(i) + ")";
  };
  const auto truncated = [&](const PlyElement& el, std::uint64_t i) {
    return Error(path, "truncated ascii data: header claims " + std::to_string(el.count) + " " +
                           el.name + " records but data ends in record " + std::to_string(i));
  };
  const auto list_count = [&](const PlyElement& el, std::uint64_t i) {
    std::uint64_t c = 0;
    if (!parse_int_token(b, e, c)) {
      throw Error(path, where(el, i) + ": cannot parse " + quote_token(b, e) + " as a list count");
    }
    return c;
  };

  for (std::size_t k = 0; k < v.index; ++k) {
    const PlyElement& el = h.elements[k];
    if (el.props.empty()) continue;  // records with no tokens: nothing to skip
    for (std::uint64_t i = 0; i < el.count; ++i) {
      for (const PlyProperty& prop : el.props) {
        if (!cur.next(b, e)) throw truncated(el, i);
        if (!prop.is_list) continue;
        for (std::uint64_t c = list_count(el, i); c > 0; --c) {
          if (!cur.next(b, e)) throw truncated(el, i);
        }
      }
    }
  }

  const PlyElement& el = h.elements[v.index];
  // Every record needs one token (>= 2 bytes with its separator) per property.
  const std::size_t min_record = 2 * el.props.size();
  if (el.count > (cur.remaining() + 1) / min_record) {
    throw ply_truncated(path, el.count, cur.remaining());
  }
  const std::size_t n = static_cast<std::size_t>(el.count);
  Cloud cloud;
  cloud.points.resize(n);
  cloud.ids_declared = v.id >= 0;
  if (v.id >= 0) cloud.ids.resize(n);
  if (v.has_color()) cloud.colors.resize(n);
  if (v.has_evidence()) cloud.evidence.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    float xyz[3] = {0.0f, 0.0f, 0.0f};
    for (std::size_t j = 0; j < el.props.size(); ++j) {
      const PlyProperty& prop = el.props[j];
      if (!cur.next(b, e)) throw truncated(el, i);
      const int slot = static_cast<int>(j);
      if (prop.is_list) {
        for (std::uint64_t c = list_count(el, i); c > 0; --c) {
          if (!cur.next(b, e)) throw truncated(el, i);
        }
      } else if (slot == v.x || slot == v.y || slot == v.z) {
        float& out = xyz[slot == v.x ? 0 : slot == v.y ? 1 : 2];
        bool ok = false;
        if (prop.type == PlyType::f32) {
          ok = parse_real_token(b, e, out);
        } else {
          double d = 0.0;
          ok = parse_real_token(b, e, d);
          out = to_float(d);
        }
        if (!ok) {
          throw Error(path, where(el, i) + ": cannot parse " + quote_token(b, e) +
                                " as a number (property " + prop.name + ")");
        }
      } else if (slot == v.id) {
        std::int64_t id = 0;
        if (!parse_int_token(b, e, id)) {
          throw Error(path,
                      where(el, i) + ": cannot parse " + quote_token(b, e) + " as an integer id");
        }
        if (id < 0) {
          throw Error(path, where(el, i) + ": negative id " + std::to_string(id));
        }
        cloud.ids[i] = static_cast<std::uint64_t>(id);
      } else if (const int c = v.color_channel(slot); c >= 0) {
        std::uint8_t* rgb[3] = {&cloud.colors[i].r, &cloud.colors[i].g, &cloud.colors[i].b};
        bool ok = false;
        if (ply_type_is_real(prop.type)) {
          double value = 0.0;
          ok = parse_real_token(b, e, value);
          *rgb[c] = colour_from_real(value);
        } else {
          std::int64_t value = 0;
          ok = parse_int_token(b, e, value) && ply_integer_fits(value, prop.type);
          *rgb[c] = colour_from_integer(value, prop.type);
        }
        if (!ok) {
          throw Error(path, where(el, i) + ": cannot parse " + quote_token(b, e) +
                                " as a colour of type " + ply_type_name(prop.type) + " (property " +
                                prop.name + ")");
        }
      } else if (v.has_evidence()) {
        for (int k = 0; k < 3; ++k) {
          if (slot != v.evidence[k]) continue;
          std::int64_t value = 0;
          if (!parse_int_token(b, e, value))
            throw Error(path, where(el, i) + ": cannot parse " + quote_token(b, e) +
                                  " as an integer " + kEvidenceNames[k]);
          set_evidence(cloud.evidence[i], k, evidence_value(path, i, k, value));
        }
      }
    }
    cloud.points[i] = Point3f{xyz[0], xyz[1], xyz[2]};
  }
  return cloud;  // elements after vertex are never looked at
}

}  // namespace detail

// Reads the vertex positions (and ids, if present) of a PLY file. Throws io::Error on any problem
// with the file; NaN/Inf coordinates are returned unchanged (see the header comment).
inline Cloud read_ply(const std::string& path) {
  const detail::FileBuffer buf = detail::read_file(path);
  const detail::PlyHeader h = detail::parse_ply_header(path, buf.data(), buf.size());
  const detail::PlyVertexLayout v = detail::locate_vertex(path, h);
  if (h.format == detail::PlyFormat::ascii) {
    return detail::read_ply_ascii(path, h, v, buf.data() + h.data_offset, buf.end());
  }
  return detail::read_ply_binary(path, h, v,
                                 reinterpret_cast<const unsigned char*>(buf.data()) + h.data_offset,
                                 buf.size() - h.data_offset);
}

// Writes "float x y z" (+ "uint id" when ids is given, + "uchar red green blue" when colors is
// given, + "uint found visible observations" when evidence is given) as binary little-endian or
// ascii PLY. ids, colors and evidence must have one entry per point and each id must fit in 32
// bits. Atomic: temp file + rename.
inline void write_ply(const std::string& path, const std::vector<Point3f>& pts,
                      const std::vector<std::uint64_t>* ids = nullptr, bool binary = true,
                      const std::vector<Rgb>* colors = nullptr,
                      const std::vector<PointEvidence>* evidence = nullptr) {
  const auto check_size = [&](std::size_t n, const char* what) {
    if (n != pts.size()) {
      throw Error(path, "write_ply: " + std::to_string(n) + " " + what + " for " +
                            std::to_string(pts.size()) + " points");
    }
  };
  if (ids) {
    check_size(ids->size(), "ids");
    for (std::size_t i = 0; i < ids->size(); ++i) {
      if ((*ids)[i] > 0xFFFFFFFFull) {
        throw Error(path, "write_ply: id " + std::to_string((*ids)[i]) + " of point " +
                              std::to_string(i) + " does not fit the 'uint' id property");
      }
    }
  }
  if (colors) check_size(colors->size(), "colours");
  if (evidence) check_size(evidence->size(), "SLAM counters");
  std::string header = "ply\nformat ";
  header += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  header += "comment written by knnocc\nelement vertex " + std::to_string(pts.size()) +
            "\nproperty float x\nproperty float y\nproperty float z\n";
  if (ids) header += "property uint id\n";
  if (colors) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (evidence)
    header += "property uint found\nproperty uint visible\nproperty uint observations\n";
  header += "end_header\n";

  AtomicFile out(path);
  out.write(header);
  if (binary) {
    const std::size_t rec = 12 + (ids ? 4 : 0) + (colors ? 3 : 0) + (evidence ? 12 : 0);
    std::vector<char> body(pts.size() * rec);
    if (rec == 12 && detail::host_is_little_endian()) {
      if (!pts.empty()) std::memcpy(body.data(), pts.data(), body.size());
    } else {
      for (std::size_t i = 0; i < pts.size(); ++i) {
        char* r = body.data() + i * rec;
        detail::store_le(r, pts[i].x);
        detail::store_le(r + 4, pts[i].y);
        detail::store_le(r + 8, pts[i].z);
        r += 12;
        if (ids) {
          detail::store_le(r, static_cast<std::uint32_t>((*ids)[i]));
          r += 4;
        }
        if (colors) {
          const Rgb c = (*colors)[i];
          r[0] = static_cast<char>(c.r);
          r[1] = static_cast<char>(c.g);
          r[2] = static_cast<char>(c.b);
          r += 3;
        }
        if (evidence) {
          const PointEvidence& e = (*evidence)[i];
          detail::store_le(r, e.found);
          detail::store_le(r + 4, e.visible);
          detail::store_le(r + 8, e.observations);
        }
      }
    }
    out.write(body.data(), body.size());
  } else {
    std::vector<char> chunk(1 << 16);
    char* w = chunk.data();
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (chunk.data() + chunk.size() - w < 256) {  // room for one full line
        out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
        w = chunk.data();
      }
      char* const lim = chunk.data() + chunk.size();
      w = detail::format_float_roundtrip(w, lim, pts[i].x);
      *w++ = ' ';
      w = detail::format_float_roundtrip(w, lim, pts[i].y);
      *w++ = ' ';
      w = detail::format_float_roundtrip(w, lim, pts[i].z);
      if (ids) {
        *w++ = ' ';
        w = std::to_chars(w, lim, (*ids)[i]).ptr;
      }
      if (colors) {
        for (const std::uint8_t v : {(*colors)[i].r, (*colors)[i].g, (*colors)[i].b}) {
          *w++ = ' ';
          w = std::to_chars(w, lim, unsigned{v}).ptr;
        }
      }
      if (evidence) {
        const PointEvidence& e = (*evidence)[i];
        for (const std::uint32_t v : {e.found, e.visible, e.observations}) {
          *w++ = ' ';
          w = std::to_chars(w, lim, v).ptr;
        }
      }
      *w++ = '\n';
    }
    out.write(chunk.data(), static_cast<std::size_t>(w - chunk.data()));
  }
  out.commit();
}

/// Writes a cloud with every column it has (ids, colours, SLAM counters); see above.
inline void write_ply_cloud(const std::string& path, const Cloud& cloud, bool binary = true) {
  write_ply(path, cloud.points, cloud.has_ids() ? &cloud.ids : nullptr, binary,
            cloud.colors.empty() ? nullptr : &cloud.colors,
            cloud.evidence.empty() ? nullptr : &cloud.evidence);
}

}  // namespace knnocc::io
