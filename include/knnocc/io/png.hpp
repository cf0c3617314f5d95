// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A tiny self-contained PNG writer (no zlib): 8-bit RGB, no filtering, the image data in
// "stored" (uncompressed) deflate blocks, with the CRC-32 of every chunk and the Adler-32 of
// the zlib stream. Files are as large as the raw pixels (3 bytes each) plus ~0.1 %; every PNG
// reader opens them. A caller with a deflate implementation (the knnocc tool uses zlib) passes
// it as `zlib_stream` and gets compressed files; the library itself needs none.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "atomic_file.hpp"
#include "error.hpp"

namespace knnocc::io {

namespace detail {

inline std::uint32_t crc32_update(std::uint32_t crc, const unsigned char* p, std::size_t n) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

inline void put_be32(std::string& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((v >> s) & 0xFFu);
}

inline void png_chunk(std::string& out, const char* type, const std::string& data) {
  put_be32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.append(type, 4);
  out += data;
  put_be32(out, crc32_update(0, reinterpret_cast<const unsigned char*>(out.data() + start),
                             out.size() - start));
}

inline std::string stored_zlib(const std::string& raw) {
  std::string z = "\x78\x01";  // deflate, 32 K window, no dictionary, fastest
  std::size_t pos = 0;
  do {
    const std::size_t n = std::min<std::size_t>(65535, raw.size() - pos);
    const bool last = pos + n == raw.size();
    z += static_cast<char>(last ? 1 : 0);  // BFINAL, BTYPE 00 (stored)
    z += static_cast<char>(n & 0xFFu);
    z += static_cast<char>(n >> 8);
    z += static_cast<char>(~n & 0xFFu);
    z += static_cast<char>((~n >> 8) & 0xFFu);
    z.append(raw, pos, n);
    pos += n;
  } while (pos < raw.size());
  std::uint32_t a = 1, b = 0;  // Adler-32
  for (const char c : raw) {
    a = (a + static_cast<unsigned char>(c)) % 65521u;
    b = (b + a) % 65521u;
  }
  put_be32(z, (b << 16) | a);
  return z;
}

}  // namespace detail

/// Turns the filtered image bytes into a complete zlib stream (header, deflate data, Adler-32).
using ZlibStream = std::function<std::string(const std::string& raw)>;

/// PNG bytes of a width x height RGB image (rgb: 3 bytes per pixel, rows top to bottom); the
/// image data in stored blocks, or compressed by `zlib_stream` when given.
inline std::string encode_png(std::uint32_t width, std::uint32_t height,
                              const std::vector<std::uint8_t>& rgb,
                              const ZlibStream& zlib_stream = {}) {
  if (width == 0 || height == 0 || rgb.size() / 3 / width != height ||
      rgb.size() != std::size_t{width} * height * 3) {
    throw Error("<png>", "image of " + std::to_string(width) + " x " + std::to_string(height) +
                             " pixels needs " + std::to_string(std::size_t{width} * height * 3) +
                             " bytes, got " + std::to_string(rgb.size()));
  }
  const std::size_t row = std::size_t{width} * 3;
  // Raw zlib payload: each row prefixed by its filter type (0: none).
  std::string raw;
  raw.reserve((row + 1) * height);
  for (std::uint32_t y = 0; y < height; ++y) {
    raw += '\0';
    raw.append(reinterpret_cast<const char*>(rgb.data()) + y * row, row);
  }
  const std::string z = zlib_stream ? zlib_stream(raw) : detail::stored_zlib(raw);

  std::string out = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  detail::put_be32(ihdr, width);
  detail::put_be32(ihdr, height);
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, no filter, no interlace
  detail::png_chunk(out, "IHDR", ihdr);
  detail::png_chunk(out, "IDAT", z);
  detail::png_chunk(out, "IEND", std::string());
  return out;
}

/// Writes the image atomically (temp file + rename).
inline void write_png(const std::string& path, std::uint32_t width, std::uint32_t height,
                      const std::vector<std::uint8_t>& rgb, const ZlibStream& zlib_stream = {}) {
  std::string bytes;
  try {
    bytes = encode_png(width, height, rgb, zlib_stream);
  } catch (const Error& e) {
    throw Error(path, e.problem());
  }
  AtomicFile out(path);
  out.write(bytes);
  out.commit();
}

}  // namespace knnocc::io
