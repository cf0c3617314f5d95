#pragma once
// A 5 x 7 pixel bitmap font (printable ASCII) for the labels of map pictures: titles, legend
// ticks, the scale bar. Glyphs drawn for this tool; characters without a glyph print as '?'.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace knnocc::cli {

/// An RGB image, rows top to bottom, 3 bytes per pixel.
struct Image {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  Image() = default;
  Image(std::uint32_t w, std::uint32_t h, std::uint8_t fill = 255)
      : width(w), height(h), rgb(std::size_t{w} * h * 3, fill) {}

  void set(std::int64_t x, std::int64_t y, const std::array<std::uint8_t, 3>& c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    std::uint8_t* p = &rgb[(static_cast<std::size_t>(y) * width + static_cast<std::size_t>(x)) * 3];
    p[0] = c[0];
    p[1] = c[1];
    p[2] = c[2];
  }
  void fill_rect(std::int64_t x0, std::int64_t y0, std::int64_t w, std::int64_t h,
                 const std::array<std::uint8_t, 3>& c) {
    for (std::int64_t y = y0; y < y0 + h; ++y)
      for (std::int64_t x = x0; x < x0 + w; ++x) set(x, y, c);
  }
  /// Copies `src` with its top-left corner at (x0, y0).
  void blit(const Image& src, std::int64_t x0, std::int64_t y0) {
    for (std::uint32_t y = 0; y < src.height; ++y)
      for (std::uint32_t x = 0; x < src.width; ++x) {
        const std::uint8_t* p = &src.rgb[(std::size_t{y} * src.width + x) * 3];
        set(x0 + x, y0 + y, {p[0], p[1], p[2]});
      }
  }
};

namespace detail {

// 35 bits per glyph, row-major from the top row, each row 5 bits (bit 4 = leftmost pixel).
inline constexpr std::array<std::uint64_t, 95> kGlyphs = {
    0x000000000ull, 0x108421004ull, 0x3A2111004ull, 0x295F57D4Aull, 0x3A2111004ull, 0x632222263ull,
    0x32544564Dull, 0x108800000ull, 0x088842082ull, 0x208210888ull, 0x009575480ull, 0x0084F9080ull,
    0x000003088ull, 0x0000F8000ull, 0x00000018Cull, 0x002222200ull, 0x3A33AE62Eull, 0x11842108Eull,
    0x3A211111Full, 0x7C441062Eull, 0x08CA97C42ull, 0x7E1E0862Eull, 0x1910F462Eull, 0x7C2222108ull,
    0x3A317462Eull, 0x3A317844Cull, 0x018C03180ull, 0x018C03088ull, 0x088882082ull, 0x001F07C00ull,
    0x208208888ull, 0x3A2111004ull, 0x3A2111004ull, 0x3A31FC631ull, 0x7A31F463Eull, 0x3A308422Eull,
    0x72518C65Cull, 0x7E10F421Full, 0x7E10F4210ull, 0x3A30BC62Full, 0x4631FC631ull, 0x38842108Eull,
    0x1C4210A4Cull, 0x4654C5251ull, 0x42108421Full, 0x4775AC631ull, 0x4639ACE31ull, 0x3A318C62Eull,
    0x7A31F4210ull, 0x3A318D64Dull, 0x7A31F5251ull, 0x3E107043Eull, 0x7C8421084ull, 0x46318C62Eull,
    0x46318C544ull, 0x4631AD6AAull, 0x462A22A31ull, 0x462A21084ull, 0x7C222221Full, 0x39084210Eull,
    0x3A2111004ull, 0x38421084Eull, 0x3A2111004ull, 0x00000001Full, 0x3A2111004ull, 0x000E0BE2Full,
    0x4216CC63Eull, 0x000E8422Eull, 0x042D9C62Full, 0x000E8FE0Eull, 0x1928E2108ull, 0x01F18BC2Eull,
    0x4216CC631ull, 0x100C2108Eull, 0x080610A4Cull, 0x4212A6292ull, 0x30842108Eull, 0x001AAD631ull,
    0x0016CC631ull, 0x000E8C62Eull, 0x001E8FA10ull, 0x000D9BC21ull, 0x0016CC210ull, 0x000E8383Eull,
    0x211C42126ull, 0x00118C66Dull, 0x00118C544ull, 0x00118D6AAull, 0x001151151ull, 0x00118BC2Eull,
    0x001F1111Full, 0x3A2111004ull, 0x108421084ull, 0x3A2111004ull, 0x3A2111004ull,
};

}  // namespace detail

inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kGlyphAdvance = 6;

/// Width in pixels of `text` at `scale` (pixels per font pixel).
inline std::int64_t text_width(const std::string& text, int scale = 1) {
  return text.empty() ? 0 : static_cast<std::int64_t>(text.size() * kGlyphAdvance - 1) * scale;
}

/// Draws `text` with its top-left corner at (x, y).
inline void draw_text(Image& img, std::int64_t x, std::int64_t y, const std::string& text,
                      const std::array<std::uint8_t, 3>& colour, int scale = 1) {
  for (const char ch : text) {
    const int code = static_cast<unsigned char>(ch);
    const std::uint64_t g =
        detail::kGlyphs[static_cast<std::size_t>(code >= 32 && code < 127 ? code - 32 : '?' - 32)];
    for (int r = 0; r < kGlyphHeight; ++r)
      for (int c = 0; c < kGlyphWidth; ++c)
        if ((g >> ((kGlyphHeight - 1 - r) * kGlyphWidth + (kGlyphWidth - 1 - c))) & 1u)
          img.fill_rect(x + c * scale, y + r * scale, scale, scale, colour);
    x += kGlyphAdvance * scale;
  }
}

}  // namespace knnocc::cli
