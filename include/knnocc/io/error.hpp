// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// knnocc::io::Error: the one exception type the IO layer throws.

#include <cstddef>
#include <stdexcept>
#include <string>

namespace knnocc::io {

namespace detail {
// Length of the UTF-8 sequence at s[i] when it is valid and encodes a printable character
// (U+00A0 and up: no C1 control), else 0.
inline std::size_t printable_utf8_length(const std::string& s, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  std::size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
    if (c == 0xC2) lo = 0xA0;  // U+0080..U+009F are C1 controls
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;  // overlong
    if (c == 0xED) hi = 0x9F;  // surrogates
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;  // overlong
    if (c == 0xF4) hi = 0x8F;  // above U+10FFFF
  }
  if (n == 0 || i + n > s.size() || byte(i + 1) < lo || byte(i + 1) > hi) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}
}  // namespace detail

/// `s` safe to print on a terminal: control characters (NUL, ESC, newline, DEL, C1) and bytes
/// that are not valid UTF-8 become `\xHH`; printable ASCII and UTF-8 characters stay. Idempotent
/// (a backslash stays a backslash), so text that was made printable once can be passed again.
inline std::string printable(const std::string& s) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t n = c >= 0x20 && c < 0x7F ? 1 : c >= 0x80 ? detail::printable_utf8_length(s, i) : 0;
    if (n) {
      out.append(s, i, n);
      i += n;
      continue;
    }
    out += "\\x";
    out += kHex[c >> 4];
    out += kHex[c & 15];
    ++i;
  }
  return out;
}

// what() is "<file>: <problem>" so a log line alone tells which input is bad. File and problem
// are kept printable(): bytes quoted from an input (a header word, a line of a file, a file
// name) cannot move the cursor or recolour a terminal, and a NUL among them does not cut the
// message short.
class Error : public std::runtime_error {
 public:
  /// `sys_errno`: the errno of the system call that failed (ENOENT for a missing file), 0 when
  /// the problem is in the content.
  Error(const std::string& file, const std::string& problem, int sys_errno = 0)
      : std::runtime_error(printable(file) + ": " + printable(problem)),
        file_(printable(file)),
        problem_(printable(problem)),
        errno_(sys_errno) {}

  const std::string& file() const noexcept { return file_; }
  const std::string& problem() const noexcept { return problem_; }
  int sys_errno() const noexcept { return errno_; }

 private:
  std::string file_;
  std::string problem_;
  int errno_ = 0;
};

}  // namespace knnocc::io
