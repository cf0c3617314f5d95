// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal helpers of the IO layer (not public API): whole-file reads, atomic writes, line and
// number scanning, fast number formatting. Every OS or parse failure becomes an io::Error.

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include "../../core/detail/huge_pages.hpp"
#include "../../core/point_traits.hpp"
#include "../atomic_file.hpp"
#include "../error.hpp"

namespace knnocc::io {

namespace detail {

// Whole file in one allocation (a large one on huge pages: it is filled completely) and one
// fread; always followed by a '\0' so strtod-style fallbacks can never run off the end.
class FileBuffer {
 public:
  const char* data() const noexcept { return data_.get(); }
  const char* end() const noexcept { return data_.get() + size_; }
  std::size_t size() const noexcept { return size_; }

 private:
  friend FileBuffer read_file(const std::string& path, bool bad_alloc_if_no_memory);
  std::unique_ptr<char[], knnocc::detail::BigFree> data_;
  std::size_t size_ = 0;
};

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// A regular file opened for reading, and its size; io::Error naming it otherwise.
inline FilePtr open_regular_file(const std::string& path, std::uintmax_t& size) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) {
    throw Error(path, "cannot open: " + (ec ? ec.message() : errno_text(ENOENT)),
                ec ? ec.value() : ENOENT);
  }
  // Sizing a directory or FIFO by seeking gives nonsense, so refuse it up front.
  if (!fs::is_regular_file(st))
    throw Error(path, "cannot open: not a regular file", fs::is_directory(st) ? EISDIR : 0);
  size = fs::file_size(path, ec);
  if (ec) throw Error(path, "cannot open: " + ec.message(), ec.value());
  FilePtr f(std::fopen(path.c_str(), "rb"));
  if (!f) {
    const int err = errno;
    throw Error(path, "cannot open: " + errno_text(err), err);
  }
  return f;
}

/// The whole file. No memory for it: io::Error naming the file, or std::bad_alloc when
/// `bad_alloc_if_no_memory` (for a caller that recovers: a group of tiles too large is halved).
inline FileBuffer read_file(const std::string& path, bool bad_alloc_if_no_memory = false) {
  std::uintmax_t size = 0;
  const FilePtr file = open_regular_file(path, size);
  std::FILE* f = file.get();
  FileBuffer buf;
  buf.size_ = static_cast<std::size_t>(size);
  // Not value-initialised: that would cost a full extra pass.
  buf.data_ = std::unique_ptr<char[], knnocc::detail::BigFree>(
      static_cast<char*>(knnocc::detail::big_alloc(buf.size_ + 1)),
      knnocc::detail::BigFree{buf.size_ + 1});
  if (!buf.data_) {
    if (bad_alloc_if_no_memory) throw std::bad_alloc();
    throw Error(path, "cannot read: out of memory for " + std::to_string(buf.size_) + " bytes");
  }
  const std::size_t got = buf.size_ ? std::fread(buf.data_.get(), 1, buf.size_, f) : 0;
  const int read_err = std::ferror(f) ? errno : 0;
  if (got != buf.size_) {
    throw Error(path, "read failed after " + std::to_string(got) + " of " +
                          std::to_string(buf.size_) + " bytes" +
                          (read_err ? ": " + errno_text(read_err) : std::string()));
  }
  buf.data_[buf.size_] = '\0';
  return buf;
}

// ---- text scanning -----------------------------------------------------------------------------

inline bool is_blank(char c) noexcept {  // whitespace inside a line
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
inline bool is_space(char c) noexcept { return c == '\n' || is_blank(c); }

// Quotes a token for an error message, cut short so a binary blob cannot flood the log.
inline std::string quote_token(const char* p, const char* end) {
  const char* e = p;
  while (e != end && !is_space(*e) && e - p < 40) ++e;
  return "'" + std::string(p, e) + "'";
}

// Double -> float without the undefined behaviour of an out-of-range conversion.
inline float to_float(double d) noexcept { return knnocc::detail::to_float(d); }

// Parses the whole token [p, e) as a float or double; false if it is not exactly one number.
// nan/inf are accepted (callers decide what non-finite means). The buffer must hold a '\0' at or
// after e (FileBuffer guarantees it) for the strtod paths.
template <class T>
bool parse_real_token(const char* p, const char* e, T& out) {
  static_assert(std::is_same_v<T, float> || std::is_same_v<T, double>);
  if (p == e) return false;
  if (*p == '+') {  // from_chars rejects a leading '+', strtod does not
    ++p;
    if (p == e || *p == '-' || *p == '+') return false;
  }
#if defined(__cpp_lib_to_chars)
  // from_chars: locale-independent and several times faster than strtod (bench/NOTES.md).
  const std::from_chars_result r = std::from_chars(p, e, out);
  if (r.ec == std::errc() && r.ptr == e) return true;
  if (r.ec != std::errc::result_out_of_range) return false;
    // Overflow/underflow: fall through to strtod, which yields +-inf or a (sub)normal/zero.
#endif
  char* stop = nullptr;
  const double d = std::strtod(p, &stop);
  if (stop != e) return false;
  if constexpr (std::is_same_v<T, float>) {
    out = to_float(d);
  } else {
    out = d;
  }
  return true;
}

template <class T>
bool parse_int_token(const char* p, const char* e, T& out) {
  if (p != e && *p == '+') ++p;
  const std::from_chars_result r = std::from_chars(p, e, out);
  return r.ec == std::errc() && r.ptr == e && p != e;
}

/// The longest text header a reader accepts (PLY, PCD, .bt/.ot, scan graph): 1 MiB, far above
/// real files' few hundred bytes. With it and linear-time parsing, no header costs more than
/// milliseconds or a few MB, however it is crafted.
inline constexpr std::size_t kMaxHeaderBytes = std::size_t{1} << 20;

/// Throws io::Error naming the file once a header has grown past kMaxHeaderBytes.
inline void check_header_length(const std::string& path, const char* format, std::size_t bytes) {
  if (bytes > kMaxHeaderBytes)
    throw Error(path, std::string(format) + " header is longer than " +
                          std::to_string(kMaxHeaderBytes >> 20) + " MiB (the limit for a header)");
}

// The blank-separated words of [p, end).
inline std::vector<std::string> split_words(const char* p, const char* end) {
  std::vector<std::string> words;
  while (true) {
    while (p != end && is_blank(*p)) ++p;
    if (p == end) break;
    const char* e = p;
    while (e != end && !is_blank(*e)) ++e;
    words.emplace_back(p, e);
    p = e;
  }
  return words;
}

// Calls fn(line_number, begin, end) for every line (1-based; '\r' before '\n' stripped; a
// UTF-8 byte-order mark before the first line, as some Windows editors write, skipped).
template <class Fn>
void for_each_line(const char* p, const char* end, Fn&& fn) {
  if (end - p >= 3 && std::memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3;
  std::size_t line = 0;
  while (p < end) {
    ++line;
    const void* nl = std::memchr(p, '\n', static_cast<std::size_t>(end - p));
    const char* le = nl ? static_cast<const char*>(nl) : end;
    const char* content_end = le;
    if (content_end != p && content_end[-1] == '\r') --content_end;
    fn(line, p, content_end);
    p = nl ? le + 1 : end;
  }
}

/// The longest line for_each_file_line() accepts (far above any text line of a real file).
inline constexpr std::size_t kMaxLineBytes = std::size_t{1} << 20;

// for_each_line() over a file read 1 MiB at a time: memory stays bounded whatever the file's size,
// and fn(line, begin, end) may stop the reading by throwing. A line longer than kMaxLineBytes is an
// io::Error naming it. Each line is followed by a '\0' in the buffer (for strtod fallbacks).
template <class Fn>
void for_each_file_line(const std::string& path, Fn&& fn) {
  std::uintmax_t size = 0;
  const FilePtr f = open_regular_file(path, size);
  std::string buf;  // unfinished line, then what was read after it
  std::size_t line = 0;
  bool first = true, eof = false;
  while (!eof) {
    const std::size_t kept = buf.size();
    buf.resize(kept + (std::size_t{1} << 20));
    const std::size_t got = std::fread(&buf[kept], 1, buf.size() - kept, f.get());
    buf.resize(kept + got);
    if (got == 0) {
      if (std::ferror(f.get())) {
        const int err = errno;
        throw Error(path, "read failed: " + errno_text(err), err);
      }
      eof = true;
    }
    if (first && buf.size() >= 3) {  // a UTF-8 byte-order mark, as for_each_line()
      if (std::memcmp(buf.data(), "\xEF\xBB\xBF", 3) == 0) buf.erase(0, 3);
      first = false;
    }
    std::size_t p = 0;
    while (true) {
      const std::size_t nl = buf.find('\n', p);
      if (nl == std::string::npos && !(eof && p < buf.size())) break;
      const std::size_t le = nl == std::string::npos ? buf.size() : nl;
      std::size_t content_end = le;
      if (content_end != p && buf[content_end - 1] == '\r') --content_end;
      ++line;
      if (le < buf.size()) buf[le] = '\0';  // the newline, never looked at again
      fn(line, buf.data() + p, buf.data() + content_end);
      p = nl == std::string::npos ? buf.size() : nl + 1;
    }
    buf.erase(0, p);
    if (buf.size() > kMaxLineBytes)
      throw Error(path, "line " + std::to_string(line + 1) + " is longer than " +
                            std::to_string(kMaxLineBytes >> 20) + " MiB");
  }
}

// Reads up to n numbers from a line into out[]; returns how many were found. Parsing stops at the
// line end, at a '#' (if hash_comments) or after n numbers (the rest of the line is ignored).
template <class T>
std::size_t scan_line_numbers(const std::string& path, std::size_t line, const char* p,
                              const char* end, T* out, std::size_t n, bool hash_comments) {
  std::size_t found = 0;
  while (found < n) {
    while (p != end && is_blank(*p)) ++p;
    if (p == end || (hash_comments && *p == '#')) break;
#if defined(__cpp_lib_to_chars)
    {  // Fast path: parse straight away, then check the number ends at a separator.
      const std::from_chars_result r = std::from_chars(p, end, out[found]);
      if (r.ec == std::errc() &&
          (r.ptr == end || is_blank(*r.ptr) || (hash_comments && *r.ptr == '#'))) {
        ++found;
        p = r.ptr;
        continue;
      }
    }
#endif
    const char* e = p;
    while (e != end && !is_blank(*e) && !(hash_comments && *e == '#')) ++e;
    if (!parse_real_token(p, e, out[found])) {
      throw Error(path, "line " + std::to_string(line) + ": cannot parse " + quote_token(p, e) +
                            " as a number");
    }
    ++found;
    p = e;
  }
  return found;
}

// Fixed "%.6f" formatting into buf (at least 350 bytes: the widest double); returns the end.
// Output is identical to printf("%.6f") (correct rounding, ties to even, "-0.000000").
inline char* format_fixed6(char* buf, char* buf_end, double v) {
  // Fast path (several times faster than to_chars): for |v| < 1e6 the product v*1e6 is below 1e12,
  // so its rounding error is under 2^-13. Unless it lies within 1e-3 of a .5 tie, the nearest
  // integer of the computed product is the nearest integer of the exact one: the printf result.
  if (std::fabs(v) < 1e6) {
    const double scaled = std::fabs(v) * 1e6;
    const double r = std::floor(scaled + 0.5);
    if (std::fabs(std::fabs(scaled - r) - 0.5) > 1e-3) {
      auto m = static_cast<std::uint64_t>(r);
      char tmp[24];
      char* t = tmp + sizeof tmp;
      for (int k = 0; k < 6; ++k, m /= 10) *--t = static_cast<char>('0' + m % 10);
      *--t = '.';
      do {
        *--t = static_cast<char>('0' + m % 10);
        m /= 10;
      } while (m != 0);
      if (std::signbit(v)) *--t = '-';
      const std::size_t n = static_cast<std::size_t>(tmp + sizeof tmp - t);
      std::memcpy(buf, t, n);
      return buf + n;
    }
  }
#if defined(__cpp_lib_to_chars)
  const std::to_chars_result r = std::to_chars(buf, buf_end, v, std::chars_format::fixed, 6);
  if (r.ec == std::errc()) return r.ptr;
#endif
  const int n = std::snprintf(buf, static_cast<std::size_t>(buf_end - buf), "%.6f", v);
  return buf + (n > 0 ? std::min<std::ptrdiff_t>(n, buf_end - buf - 1) : 0);
}

// Shortest text that reads back to the same float.
inline char* format_float_roundtrip(char* buf, char* buf_end, float v) {
#if defined(__cpp_lib_to_chars)
  const std::to_chars_result r = std::to_chars(buf, buf_end, v);
  if (r.ec == std::errc()) return r.ptr;
#endif
  const int n =
      std::snprintf(buf, static_cast<std::size_t>(buf_end - buf), "%.9g", static_cast<double>(v));
  return buf + (n > 0 ? std::min<std::ptrdiff_t>(n, buf_end - buf - 1) : 0);
}

// The shortest "%g" text that reads back to the same double (for messages that compare values:
// 0.1 and 0.1000001 must not both print as 0.100000).
inline std::string round_trip_text(double v) {
  char text[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

}  // namespace detail
}  // namespace knnocc::io
