// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Internal: loading and storing fixed-size binary values in a given byte order (memcpy only, so
// unaligned input is fine and there is no type punning).

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace knnocc::io::detail {

inline bool host_is_little_endian() noexcept {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// A T stored at p, byte-reversed when swap is set.
template <class T>
T load_scalar(const unsigned char* p, bool swap) noexcept {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (swap) std::reverse(b, b + sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

template <class T>
T load_le(const unsigned char* p) noexcept {
  return load_scalar<T>(p, !host_is_little_endian());
}

template <class T>
void store_le(char* out, T value) noexcept {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (!host_is_little_endian()) std::reverse(b, b + sizeof(T));
  std::memcpy(out, b, sizeof(T));
}

template <class T>
void store_be(char* out, T value) noexcept {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if (host_is_little_endian()) std::reverse(b, b + sizeof(T));
  std::memcpy(out, b, sizeof(T));
}

}  // namespace knnocc::io::detail
