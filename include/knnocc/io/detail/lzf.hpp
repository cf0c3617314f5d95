// SPDX-License-Identifier: BSD-3-Clause
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
#include <utility>
#include <vector>

namespace knnocc::io::detail {

inline constexpr std::size_t kLzfMaxRatio = 88;  // 264 output bytes per 3 input bytes

inline constexpr std::size_t kLzfReach = 8192;  // the farthest a back reference looks back

/// Decodes `in`, declared to give exactly `out_size` bytes, into `out`, a sink with
/// literal(const unsigned char* src, std::size_t n) and repeat(std::size_t dist, std::size_t n)
/// (copy n bytes starting dist bytes back; the copy may overlap itself). Returns "" on success,
/// else what is wrong with the stream; the sink is only asked for what the bytes so far allow
/// (it never reads outside `in`, a reference never reaches before the first output byte, the
/// output never exceeds out_size).
template <class Sink>
std::string lzf_decode(const unsigned char* in, std::size_t in_size, std::size_t out_size,
                       Sink& out) {
  std::size_t ip = 0, op = 0;
  while (ip < in_size) {
    const unsigned ctrl = in[ip++];
    if (ctrl < 32) {
      const std::size_t n = ctrl + 1;
      if (n > in_size - ip) return "LZF literal run runs past the end of the compressed data";
      if (n > out_size - op) return "LZF data decodes to more bytes than declared";
      out.literal(in + ip, n);
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
    out.repeat(dist, len);
    op += len;
  }
  if (op != out_size) {
    return "LZF data decodes to " + std::to_string(op) + " bytes, not the declared " +
           std::to_string(out_size);
  }
  return {};
}

/// Copies n bytes from dist bytes before `to` to `to`: an overlapping copy (dist < n) repeats the
/// last dist bytes, done here in non-overlapping blocks that double in length.
inline void lzf_repeat(unsigned char* to, std::size_t dist, std::size_t n) {
  const unsigned char* const from = to - dist;
  if (dist == 1) {
    std::memset(to, *from, n);
    return;
  }
  std::size_t span = dist;  // bytes from `from` that already repeat the pattern
  while (n > 0) {
    const std::size_t c = std::min(span, n);
    std::memcpy(to, from, c);
    to += c;
    n -= c;
    span += c;
  }
}

/// Decodes `in` into exactly `out_size` bytes at `out`. Returns "" on success, else what is
/// wrong with the stream (it never reads or writes outside the two buffers).
inline std::string lzf_decompress(const unsigned char* in, std::size_t in_size, unsigned char* out,
                                  std::size_t out_size) {
  struct Buffer {
    unsigned char* at;
    void literal(const unsigned char* src, std::size_t n) {
      std::memcpy(at, src, n);
      at += n;
    }
    void repeat(std::size_t dist, std::size_t n) {
      lzf_repeat(at, dist, n);
      at += n;
    }
  } sink{out};
  return lzf_decode(in, in_size, out_size, sink);
}

/// What is wrong with `in` as a stream of exactly out_size bytes ("" if nothing), without
/// producing the bytes: readers check a stream this way before allocating for its content.
inline std::string lzf_check(const unsigned char* in, std::size_t in_size, std::size_t out_size) {
  struct Nothing {
    void literal(const unsigned char*, std::size_t) {}
    void repeat(std::size_t, std::size_t) {}
  } sink;
  return lzf_decode(in, in_size, out_size, sink);
}

/// A sink for lzf_decode that hands the decoded bytes to consume(offset, data, n) piece by piece,
/// in order, each byte once, holding only one piece and the last kLzfReach bytes: a reader takes
/// what it needs from a large stream without the whole of it in memory. Call finish() after a
/// successful lzf_decode to hand over the last piece.
template <class Consume>
class LzfPieces {
 public:
  explicit LzfPieces(Consume consume, std::size_t piece = std::size_t{1} << 16)
      : consume_(std::move(consume)), buf_(kLzfReach + std::max<std::size_t>(piece, 264)) {}

  void literal(const unsigned char* src, std::size_t n) {
    make_room(n);
    std::memcpy(buf_.data() + end_, src, n);
    end_ += n;
  }
  void repeat(std::size_t dist, std::size_t n) {
    make_room(n);
    lzf_repeat(buf_.data() + end_, dist, n);
    end_ += n;
  }
  void finish() { hand_over(); }

 private:
  void hand_over() {
    if (end_ > handed_) consume_(offset_ + handed_, buf_.data() + handed_, end_ - handed_);
    handed_ = end_;
  }
  // Hands over every byte not yet handed over and keeps the last kLzfReach for references.
  void make_room(std::size_t n) {
    if (end_ + n <= buf_.size()) return;
    hand_over();
    const std::size_t keep = std::min(end_, kLzfReach);
    std::memmove(buf_.data(), buf_.data() + end_ - keep, keep);
    offset_ += end_ - keep;
    end_ = handed_ = keep;
  }

  Consume consume_;
  std::vector<unsigned char> buf_;
  std::uint64_t offset_ = 0;  // stream offset of buf_[0]
  std::size_t end_ = 0;       // bytes of buf_ in use
  std::size_t handed_ = 0;    // bytes of buf_ already handed over
};

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
    if (ref != kNone && i - ref <= kLzfReach && std::memcmp(in + ref, in + i, 3) == 0) {
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
