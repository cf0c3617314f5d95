// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One YAML scalar on one line, for the flat "key: value" files knnocc writes and reads (ROS map
// YAML, ros_map.hpp): written double-quoted, so that any YAML parser (yaml-cpp in map_server and
// Nav2, PyYAML) reads back exactly the text given, whatever a file name holds ('#', ': ', quotes,
// a leading '-' or '[', a newline); read in any of the three one-line styles.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "../error.hpp"  // printable_utf8_length

namespace knnocc::io::detail {

/// Appends code point `cp` as UTF-8.
inline void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

/// `s` as a YAML double-quoted scalar (quotes included) into `out`: '"' and '\' escaped, control
/// characters (C0, DEL, C1) as \n \t \r or \xHH, the characters a parser would take as a line
/// break or refuse (U+2028, U+2029, U+FEFF, U+FFFE, U+FFFF) as \uHHHH; other UTF-8 as it is.
/// False when `s` is not valid UTF-8: YAML text is Unicode, so no escape stands for a raw byte.
inline bool yaml_double_quoted(const std::string& s, std::string& out) {
  static const char kHex[] = "0123456789ABCDEF";
  const auto hex = [&](std::uint32_t v, int digits) {
    for (int d = digits - 1; d >= 0; --d) out += kHex[(v >> (4 * d)) & 15];
  };
  out = "\"";
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      if (c == '"' || c == '\\') {
        out += '\\';
        out += static_cast<char>(c);
      } else if (c == '\n') {
        out += "\\n";
      } else if (c == '\t') {
        out += "\\t";
      } else if (c == '\r') {
        out += "\\r";
      } else if (c < 0x20 || c == 0x7F) {
        out += "\\x";
        hex(c, 2);
      } else {
        out += static_cast<char>(c);
      }
      ++i;
      continue;
    }
    const std::size_t n = printable_utf8_length(s, i);
    if (n == 0) {  // a C1 control (U+0080..U+009F, C2 80..C2 9F), or not UTF-8
      const auto next = i + 1 < s.size() ? static_cast<unsigned char>(s[i + 1]) : 0u;
      if (c != 0xC2 || next < 0x80 || next > 0x9F) return false;
      out += "\\x";
      hex(next, 2);
      i += 2;
      continue;
    }
    std::uint32_t cp = n == 2 ? c & 0x1Fu : n == 3 ? c & 0x0Fu : c & 0x07u;
    for (std::size_t k = 1; k < n; ++k)
      cp = (cp << 6) | (static_cast<unsigned char>(s[i + k]) & 0x3Fu);
    if (cp == 0x2028 || cp == 0x2029 || cp == 0xFEFF || cp == 0xFFFE || cp == 0xFFFF) {
      out += "\\u";
      hex(cp, 4);
    } else {
      out.append(s, i, n);
    }
    i += n;
  }
  out += '"';
  return true;
}

/// The value of a one-line YAML scalar [b, e) (no leading blanks): double-quoted (with YAML's
/// escapes), single-quoted ('' for a quote) or plain (up to a " #" comment, trailing blanks
/// dropped). False for a quoted scalar that is not closed, a bad escape, or text after it other
/// than blanks and a comment.
inline bool yaml_scalar(const char* b, const char* e, std::string& out) {
  out.clear();
  const auto rest_is_comment = [&](const char* p) {
    while (p != e && (*p == ' ' || *p == '\t')) ++p;
    return p == e || *p == '#';
  };
  if (b != e && *b == '\'') {
    for (const char* p = b + 1; p != e; ++p) {
      if (*p != '\'') {
        out += *p;
      } else if (p + 1 != e && p[1] == '\'') {
        out += '\'';
        ++p;
      } else {
        return rest_is_comment(p + 1);
      }
    }
    return false;
  }
  if (b != e && *b == '"') {
    const auto hex_digits = [&](const char*& p, int digits, std::uint32_t& v) {
      v = 0;
      for (int d = 0; d < digits; ++d) {
        if (++p == e) return false;
        const char h = *p;
        const int x = h >= '0' && h <= '9'   ? h - '0'
                      : h >= 'a' && h <= 'f' ? h - 'a' + 10
                      : h >= 'A' && h <= 'F' ? h - 'A' + 10
                                             : -1;
        if (x < 0) return false;
        v = v * 16 + static_cast<std::uint32_t>(x);
      }
      return true;
    };
    for (const char* p = b + 1; p != e; ++p) {
      if (*p == '"') return rest_is_comment(p + 1);
      if (*p != '\\') {
        out += *p;
        continue;
      }
      if (++p == e) return false;
      // YAML's escapes: \0 \a \b \t \n \v \f \r \e, an escaped tab, space, " / and \.
      static const char kEscape[] = "0abtnvfre\t \"/\\";
      static const char kMeans[] = "\0\a\b\t\n\v\f\r\x1b\t \"/\\";
      if (const char* at = std::strchr(kEscape, *p); at && *p) {
        out += kMeans[at - kEscape];
        continue;
      }
      std::uint32_t v = *p == 'N' ? 0x85 : *p == '_' ? 0xA0 : *p == 'L' ? 0x2028 : 0x2029;
      if (*p == 'x' || *p == 'u' || *p == 'U') {
        const int digits = *p == 'x' ? 2 : *p == 'u' ? 4 : 8;
        if (!hex_digits(p, digits, v) || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return false;
      } else if (*p != 'N' && *p != '_' && *p != 'L' && *p != 'P') {
        return false;
      }
      append_utf8(out, v);
    }
    return false;
  }
  const char* end = b;
  for (const char* p = b; p != e; ++p) {
    if (*p == '#' && p != b && (p[-1] == ' ' || p[-1] == '\t')) break;
    end = p + 1;
  }
  while (end != b && (end[-1] == ' ' || end[-1] == '\t')) --end;
  out.assign(b, end);
  return true;
}

}  // namespace knnocc::io::detail
