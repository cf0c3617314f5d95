#pragma once
// Rgb: an 8-bit colour, as point files (PLY red/green/blue, PCD rgb/rgba) and OctoMap's
// ColorOcTree store it.

#include <cstdint>

namespace knnocc {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;

  friend bool operator==(const Rgb& a, const Rgb& c) {
    return a.r == c.r && a.g == c.g && a.b == c.b;
  }
  friend bool operator!=(const Rgb& a, const Rgb& c) { return !(a == c); }
};

}  // namespace knnocc
