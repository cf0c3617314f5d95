#pragma once
// Internal: the LZF compression format (Marc Lehmann's liblzf) used by PCD "binary_compressed".
//
// A stream is a sequence of runs, each starting with a control byte c:
//   c < 32           a literal run: the next c + 1 bytes are copied to the output;
//   c >= 32          a back reference: length L = c >> 5 (7 means "7 + the next byte"),
//                    distance D = ((c & 31) << 8 | the following byte) + 1; copy L + 2 bytes
//                    starting D bytes back in the output (the copy may overlap itself).
// One reference produces at most 264 bytes from 3 input bytes, so a stream never expands by more
// than kLzfMaxRatio: readers check a claimed output size against that before allocating it.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace knnocc::io::detail {

inline constexpr std::size_t kLzfMaxRatio = 88;  // 264 output bytes per 3 input bytes

/// Decodes `in` into exactly `out_size` bytes at `out`. Returns "" on success, else what is
/// wrong with the stream (it never reads or writes outside the two buffers).
inline std::string lzf_decompress(const unsigned char* in, std::size_t in_size, unsigned char* out,
                                  std::size_t out_size) {
  std::size_t ip = 0, op = 0;
  while (ip < in_size) {
    const unsigned ctrl = in[ip++];
    if (ctrl < 32) {
      const std::size_t n = ctrl + 1;
      if (n > in_size - ip) return "LZF literal run runs past the end of the compressed data";
      if (n > out_size - op) return "LZF data decodes to more bytes than declared";
      std::memcpy(out + op, in + ip, n);
      ip += n;
      op += n;
      continue;
    }
    std::size_t len = ctrl >> 5;
    if (len == 7) {
      if (ip >= in_size) return "LZF back reference cut off at the end of the data";
      len += in[ip++];
    }
    if (ip >= in_size) return "LZF back reference cut off at the end of the data";
    const std::size_t dist = ((std::size_t{ctrl} & 31u) << 8 | in[ip++]) + 1;
    len += 2;
    if (dist > op) return "LZF back reference points before the start of the output";
    if (len > out_size - op) return "LZF data decodes to more bytes than declared";
    for (std::size_t k = 0; k < len; ++k, ++op) out[op] = out[op - dist];  // may overlap
  }
  if (op != out_size) {
    return "LZF data decodes to " + std::to_string(op) + " bytes, not the declared " +
           std::to_string(out_size);
  }
  return {};
}

/// A valid LZF stream for `in` (greedy matching over a hash of 3-byte sequences).
inline std::vector<unsigned char> lzf_compress(const unsigned char* in, std::size_t n) {
  std::vector<unsigned char> out;
  out.reserve(n + n / 32 + 16);
  constexpr int kHashBits = 14;
  constexpr std::size_t kNone = ~std::size_t{0};
  std::vector<std::size_t> table(std::size_t{1} << kHashBits, kNone);
  std::size_t lit = 0;  // start of the pending literal bytes
  auto flush_literals = [&](std::size_t end) {
    while (lit < end) {
      const std::size_t k = std::min<std::size_t>(32, end - lit);
      out.push_back(static_cast<unsigned char>(k - 1));
      out.insert(out.end(), in + lit, in + lit + k);
      lit += k;
    }
  };
  std::size_t i = 0;
  while (i + 2 < n) {
    const std::uint32_t v =
        (std::uint32_t{in[i]} << 16) | (std::uint32_t{in[i + 1]} << 8) | in[i + 2];
    const std::size_t h = (v * 2654435761u) >> (32 - kHashBits);
    const std::size_t ref = table[h];
    table[h] = i;
    if (ref != kNone && i - ref <= 8192 && std::memcmp(in + ref, in + i, 3) == 0) {
      const std::size_t max_len = std::min<std::size_t>(264, n - i);
      std::size_t len = 3;
      while (len < max_len && in[ref + len] == in[i + len]) ++len;
      flush_literals(i);
      const std::size_t l = len - 2, off = i - ref - 1;
      const auto high = static_cast<unsigned char>(off >> 8);
      if (l < 7) {
        out.push_back(static_cast<unsigned char>((l << 5) | high));
      } else {
        out.push_back(static_cast<unsigned char>((7u << 5) | high));
        out.push_back(static_cast<unsigned char>(l - 7));
      }
      out.push_back(static_cast<unsigned char>(off & 0xffu));
      i += len;
      lit = i;
    } else {
      ++i;
    }
  }
  flush_literals(n);
  return out;
}

}  // namespace knnocc::io::detail
