// LZF codec: decoding arbitrary bytes never touches memory outside its buffers (ASan), checking
// a stream and decoding it in pieces agree with decoding it into one buffer, and
// compress -> decompress gives the input back.
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <knnocc/io/detail/lzf.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // Arbitrary stream, arbitrary declared size (up to 64 KiB).
  const std::size_t declared = (std::size_t{data[0]} << 8 | data[1]);
  std::vector<unsigned char> out(declared);
  const std::string problem =
      knnocc::io::detail::lzf_decompress(data + 2, size - 2, out.data(), out.size());
  // The check finds what decoding finds; decoding in pieces gives the same bytes.
  if (knnocc::io::detail::lzf_check(data + 2, size - 2, declared) != problem) std::abort();
  std::vector<unsigned char> pieces_out;
  knnocc::io::detail::LzfPieces pieces(
      [&](std::uint64_t offset, const unsigned char* p, std::size_t n) {
        if (offset != pieces_out.size()) std::abort();
        pieces_out.insert(pieces_out.end(), p, p + n);
      },
      97);
  if (knnocc::io::detail::lzf_decode(data + 2, size - 2, declared, pieces) != problem) std::abort();
  pieces.finish();
  if (problem.empty() && pieces_out != out) std::abort();
  // Round trip.
  const std::vector<unsigned char> packed = knnocc::io::detail::lzf_compress(data, size);
  std::vector<unsigned char> back(size);
  const std::string err =
      knnocc::io::detail::lzf_decompress(packed.data(), packed.size(), back.data(), back.size());
  if (!err.empty() || std::memcmp(back.data(), data, size) != 0) std::abort();
  return 0;
}
