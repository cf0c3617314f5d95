// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// SHA-256 (FIPS 180-4), fed in pieces: the checksums of a tile set's files (tiles/tile_set.hpp),
// which `sha256sum` checks too, and the view page's Content-Security-Policy hashes.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#if !defined(KNNOCC_NO_SIMD) && (defined(__GNUC__) || defined(__clang__)) && defined(__x86_64__)
#define KNNOCC_SHA_NI 1
#include <cpuid.h>
#include <immintrin.h>
#else
#define KNNOCC_SHA_NI 0
#endif

namespace knnocc::io::detail {

inline constexpr std::uint32_t kSha256Round[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

#if KNNOCC_SHA_NI
/// The CPU has the SHA extensions (checked once).
inline bool cpu_has_sha() {
  static const bool has = [] {
    unsigned a = 0, b = 0, c = 0, d = 0;
    if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
    const bool sha = (b >> 29) & 1u;
    if (!__get_cpuid(1, &a, &b, &c, &d)) return false;
    const bool sse41 = (c >> 19) & 1u, ssse3 = (c >> 9) & 1u;
    return sha && sse41 && ssse3;
  }();
  return has;
}

/// `blocks` 64-byte blocks into the state h[8], with the SHA extensions: the same rounds as the
/// portable compression, four at a time (the message schedule by sha256msg1/msg2).
__attribute__((target("sha,sse4.1,ssse3"))) inline void sha256_blocks_ni(std::uint32_t* h,
                                                                         const unsigned char* m,
                                                                         std::size_t blocks) {
  const __m128i swap = _mm_set_epi64x(0x0c0d0e0f08090a0bLL, 0x0405060700010203LL);
  __m128i t = _mm_loadu_si128(reinterpret_cast<const __m128i*>(h));       // D C B A
  __m128i s1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(h + 4));  // H G F E
  t = _mm_shuffle_epi32(t, 0xB1);                                         // C D A B
  s1 = _mm_shuffle_epi32(s1, 0x1B);                                       // E F G H
  __m128i s0 = _mm_alignr_epi8(t, s1, 8);                                 // A B E F
  s1 = _mm_blend_epi16(s1, t, 0xF0);                                      // C D G H
  for (; blocks > 0; --blocks, m += 64) {
    const __m128i abef = s0, cdgh = s1;
    __m128i w[4];
    for (int i = 0; i < 16; ++i) {
      __m128i wi;
      if (i < 4) {
        wi = _mm_shuffle_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(m + 16 * i)), swap);
      } else {
        const __m128i x = _mm_add_epi32(_mm_sha256msg1_epu32(w[i % 4], w[(i + 1) % 4]),
                                        _mm_alignr_epi8(w[(i + 3) % 4], w[(i + 2) % 4], 4));
        wi = _mm_sha256msg2_epu32(x, w[(i + 3) % 4]);
      }
      w[i % 4] = wi;
      __m128i k = _mm_add_epi32(
          wi, _mm_loadu_si128(reinterpret_cast<const __m128i*>(kSha256Round + 4 * i)));
      s1 = _mm_sha256rnds2_epu32(s1, s0, k);
      k = _mm_shuffle_epi32(k, 0x0E);
      s0 = _mm_sha256rnds2_epu32(s0, s1, k);
    }
    s0 = _mm_add_epi32(s0, abef);
    s1 = _mm_add_epi32(s1, cdgh);
  }
  t = _mm_shuffle_epi32(s0, 0x1B);    // F E B A
  s1 = _mm_shuffle_epi32(s1, 0xB1);   // D C H G
  s0 = _mm_blend_epi16(t, s1, 0xF0);  // D C B A
  s1 = _mm_alignr_epi8(s1, t, 8);     // H G F E
  _mm_storeu_si128(reinterpret_cast<__m128i*>(h), s0);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(h + 4), s1);
}
#endif

class Sha256 {
 public:
  /// `simd`: use the SHA extensions where the CPU has them (false: the portable rounds, which
  /// the tests compare them with).
  explicit Sha256(bool simd = true) : simd_(simd) {}

  /// Adds n bytes of the message.
  void update(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    length_ += n;
    if (used_ > 0) {
      while (n > 0 && used_ < 64) {
        block_[used_++] = *p++;
        --n;
      }
      if (used_ < 64) return;
      compress(block_);
      used_ = 0;
    }
    if (n >= 64) {
      blocks(p, n / 64);
      p += n / 64 * 64;
      n %= 64;
    }
    for (; n > 0; --n) block_[used_++] = *p++;
  }
  void update(const std::string& s) { update(s.data(), s.size()); }

  /// The 32-byte digest of everything added (the object is spent afterwards).
  std::array<std::uint8_t, 32> digest() {
    const std::uint64_t bits = length_ * 8;
    const unsigned char one = 0x80, zero = 0;
    update(&one, 1);
    while (used_ != 56) update(&zero, 1);
    unsigned char len[8];
    for (int i = 0; i < 8; ++i) len[i] = static_cast<unsigned char>(bits >> (56 - 8 * i));
    update(len, 8);
    std::array<std::uint8_t, 32> out{};
    for (int i = 0; i < 32; ++i)
      out[i] = static_cast<std::uint8_t>(h_[i / 4] >> (24 - 8 * (i % 4)));
    return out;
  }

  /// The digest as 64 lowercase hex digits (sha256sum's form).
  std::string hex() {
    const auto d = digest();
    std::string out;
    char two[3];
    for (const std::uint8_t b : d) {
      std::snprintf(two, sizeof two, "%02x", b);
      out += two;
    }
    return out;
  }

 private:
  static std::uint32_t rotr(std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

  void compress(const unsigned char* m) { blocks(m, 1); }

  // n 64-byte blocks, with the SHA extensions when the CPU has them.
  void blocks(const unsigned char* m, std::size_t n) {
#if KNNOCC_SHA_NI
    if (simd_ && cpu_has_sha()) {
      sha256_blocks_ni(h_, m, n);
      return;
    }
#endif
    for (; n > 0; --n, m += 64) portable(m);
  }

  void portable(const unsigned char* m) {
    const std::uint32_t* k = kSha256Round;
    std::uint32_t w[64];
    for (int i = 0; i < 16; ++i)
      w[i] = (std::uint32_t{m[4 * i]} << 24) | (std::uint32_t{m[4 * i + 1]} << 16) |
             (std::uint32_t{m[4 * i + 2]} << 8) | std::uint32_t{m[4 * i + 3]};
    for (int i = 16; i < 64; ++i) {
      const std::uint32_t s0 = rotr(w[i - 15], 7) ^ rotr(w[i - 15], 18) ^ (w[i - 15] >> 3);
      const std::uint32_t s1 = rotr(w[i - 2], 17) ^ rotr(w[i - 2], 19) ^ (w[i - 2] >> 10);
      w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    std::uint32_t a = h_[0], b = h_[1], c = h_[2], d = h_[3], e = h_[4], f = h_[5], g = h_[6],
                  hh = h_[7];
    for (int i = 0; i < 64; ++i) {
      const std::uint32_t t1 =
          hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[i] + w[i];
      const std::uint32_t t2 =
          (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      hh = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    const std::uint32_t add[8] = {a, b, c, d, e, f, g, hh};
    for (int i = 0; i < 8; ++i) h_[i] += add[i];
  }

  std::uint32_t h_[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                         0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  unsigned char block_[64] = {};
  std::size_t used_ = 0;
  std::uint64_t length_ = 0;
  bool simd_ = true;
};

/// The 32-byte SHA-256 digest of `data`.
inline std::array<std::uint8_t, 32> sha256(const std::string& data) {
  Sha256 h;
  h.update(data);
  return h.digest();
}

}  // namespace knnocc::io::detail
