#pragma once
// PNG files of the tool, deflated with zlib (level 9) when the tool is built with it
// (KNNOCC_TOOL_ZLIB); otherwise the library's uncompressed writer.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <knnocc/io/png.hpp>

#ifdef KNNOCC_TOOL_ZLIB
#include <zlib.h>
#endif

namespace knnocc::cli {

/// The zlib stream of `raw` (compress2, best compression); empty function without zlib.
inline io::ZlibStream zlib_deflate() {
#ifdef KNNOCC_TOOL_ZLIB
  return [](const std::string& raw) {
    uLongf size = compressBound(static_cast<uLong>(raw.size()));
    std::string out(size, '\0');
    if (compress2(reinterpret_cast<Bytef*>(out.data()), &size,
                  reinterpret_cast<const Bytef*>(raw.data()), static_cast<uLong>(raw.size()),
                  Z_BEST_COMPRESSION) != Z_OK)
      throw std::runtime_error("zlib could not compress the image");
    out.resize(size);
    return out;
  };
#else
  return {};
#endif
}

inline void write_png_compressed(const std::string& path, std::uint32_t width, std::uint32_t height,
                                 const std::vector<std::uint8_t>& rgb) {
  io::write_png(path, width, height, rgb, zlib_deflate());
}

}  // namespace knnocc::cli
