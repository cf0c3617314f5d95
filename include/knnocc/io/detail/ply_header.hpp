// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The header of a PLY file (io/ply.hpp reads the body): its format, its elements and their scalar
// and list properties, with each property's type and offset in a binary record. Every problem
// with the header throws io::Error naming the file.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_set>
#include <vector>

#include "../error.hpp"
#include "bytes.hpp"
#include "file_text.hpp"

namespace knnocc::io::detail {

enum class PlyType : std::uint8_t { i8, u8, i16, u16, i32, u32, f32, f64 };
enum class PlyFormat : std::uint8_t { ascii, binary_le, binary_be };

inline bool ply_type_from_name(const std::string& s, PlyType& t) {
  struct Entry {
    const char* name;
    PlyType type;
  };
  static const Entry table[] = {
      {"char", PlyType::i8},     {"int8", PlyType::i8},     {"uchar", PlyType::u8},
      {"uint8", PlyType::u8},    {"short", PlyType::i16},   {"int16", PlyType::i16},
      {"ushort", PlyType::u16},  {"uint16", PlyType::u16},  {"int", PlyType::i32},
      {"int32", PlyType::i32},   {"uint", PlyType::u32},    {"uint32", PlyType::u32},
      {"float", PlyType::f32},   {"float32", PlyType::f32}, {"double", PlyType::f64},
      {"float64", PlyType::f64},
  };
  for (const Entry& e : table) {
    if (s == e.name) {
      t = e.type;
      return true;
    }
  }
  return false;
}

inline std::size_t ply_type_size(PlyType t) noexcept {
  switch (t) {
    case PlyType::i8:
    case PlyType::u8:
      return 1;
    case PlyType::i16:
    case PlyType::u16:
      return 2;
    case PlyType::i32:
    case PlyType::u32:
    case PlyType::f32:
      return 4;
    case PlyType::f64:
      return 8;
  }
  return 0;
}

// The type's name in error messages (the PLY 1.0 spelling).
inline const char* ply_type_name(PlyType t) noexcept {
  static const char* const names[] = {"char", "uchar", "short", "ushort",
                                      "int",  "uint",  "float", "double"};
  return names[static_cast<int>(t)];
}

inline bool ply_type_is_real(PlyType t) noexcept { return t == PlyType::f32 || t == PlyType::f64; }
inline bool ply_type_is_signed(PlyType t) noexcept {
  return t == PlyType::i8 || t == PlyType::i16 || t == PlyType::i32;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::u8;  // item type for lists
  bool is_list = false;
  PlyType count_type = PlyType::u8;  // lists only
  std::size_t offset = 0;            // byte offset in a binary record (scalar-only elements)
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> props;

  const PlyProperty* first_list() const {
    for (const PlyProperty& p : props) {
      if (p.is_list) return &p;
    }
    return nullptr;
  }
  std::size_t record_size() const {  // binary bytes per record; scalar-only elements
    std::size_t n = 0;
    for (const PlyProperty& p : props) n += ply_type_size(p.type);
    return n;
  }
  int find(const char* prop_name) const {
    for (std::size_t i = 0; i < props.size(); ++i) {
      if (props[i].name == prop_name) return static_cast<int>(i);
    }
    return -1;
  }
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  std::size_t data_offset = 0;  // first byte after the end_header line
  std::size_t line_count = 0;   // header lines, so ascii errors can report file line numbers
};

inline PlyHeader parse_ply_header(const std::string& path, const char* data, std::size_t size) {
  PlyHeader h;
  bool have_format = false;
  const char* p = data;
  const char* const end = data + size;
  std::size_t line = 0;
  // Check the magic line by hand: splitting a large non-PLY file into "words" would be slow.
  {
    const char* q = data + 3;
    if (size < 3 || std::memcmp(data, "ply", 3) != 0) q = nullptr;
    while (q && q != end && is_blank(*q)) ++q;
    if (!q || (q != end && *q != '\n')) {
      throw Error(path, "not a PLY file (first line is not 'ply')");
    }
  }
  // Names seen so far (the checks for duplicates stay linear in the header's length) and the
  // current element's record size.
  std::unordered_set<std::string> element_names, property_names;
  std::size_t record_bytes = 0;
  while (true) {
    if (p == end) throw Error(path, "PLY header has no end_header line");
    ++line;
    const void* nl = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
    const char* le = nl ? static_cast<const char*>(nl) : end;
    check_header_length(path, "PLY", static_cast<std::size_t>(le - data));
    const char* next = nl ? le + 1 : end;
    const std::vector<std::string> w = split_words(p, le);
    p = next;
    const auto bad = [&](const std::string& why) {
      return Error(path, "PLY header line " + std::to_string(line) + ": " + why);
    };

    if (line == 1 || w.empty()) continue;  // line 1 is the magic checked above
    const std::string& key = w[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      if (w.size() != 1) throw bad("unexpected text after end_header");
      break;
    }
    if (key == "format") {
      if (w.size() < 2) throw bad("format line names no format");
      if (w[1] == "ascii") {
        h.format = PlyFormat::ascii;
      } else if (w[1] == "binary_little_endian") {
        h.format = PlyFormat::binary_le;
      } else if (w[1] == "binary_big_endian") {
        h.format = PlyFormat::binary_be;
      } else {
        throw bad("unknown PLY format '" + w[1] + "'");
      }
      have_format = true;
    } else if (key == "element") {
      if (w.size() != 3) throw bad("expected 'element <name> <count>'");
      PlyElement el;
      el.name = w[1];
      if (!parse_int_token(w[2].data(), w[2].data() + w[2].size(), el.count)) {
        throw bad("invalid element count '" + w[2] + "'");
      }
      if (!element_names.insert(el.name).second) throw bad("duplicate element '" + el.name + "'");
      property_names.clear();
      record_bytes = 0;
      h.elements.push_back(std::move(el));
    } else if (key == "property") {
      if (h.elements.empty()) throw bad("property before any element");
      PlyProperty prop;
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) throw bad("expected 'property list <count type> <type> <name>'");
        if (!ply_type_from_name(w[2], prop.count_type)) {
          throw bad("unknown PLY property type '" + w[2] + "'");
        }
        if (ply_type_is_real(prop.count_type)) {
          throw bad("list count type must be an integer type, not '" + w[2] + "'");
        }
        if (!ply_type_from_name(w[3], prop.type)) {
          throw bad("unknown PLY property type '" + w[3] + "'");
        }
        prop.is_list = true;
        prop.name = w[4];
      } else {
        if (w.size() != 3) throw bad("expected 'property <type> <name>'");
        if (!ply_type_from_name(w[1], prop.type)) {
          throw bad("unknown PLY property type '" + w[1] + "'");
        }
        prop.name = w[2];
      }
      PlyElement& el = h.elements.back();
      if (!property_names.insert(prop.name).second) {
        throw bad("duplicate property '" + prop.name + "' in element '" + el.name + "'");
      }
      prop.offset = record_bytes;
      record_bytes += ply_type_size(prop.type);
      el.props.push_back(std::move(prop));
    } else {
      throw bad("unknown PLY header keyword '" + key + "'");
    }
  }
  if (!have_format) throw Error(path, "PLY header has no format line");
  h.data_offset = static_cast<std::size_t>(p - data);
  h.line_count = line;
  return h;
}

}  // namespace knnocc::io::detail
