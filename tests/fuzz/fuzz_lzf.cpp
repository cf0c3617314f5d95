// LZF codec: decoding arbitrary bytes never touches memory outside its buffers (ASan), and
// compress -> decompress gives the input back.
#include <cstring>
#include <vector>

#include <knnocc/io/detail/lzf.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  // Arbitrary stream, arbitrary declared size (up to 64 KiB).
  const std::size_t declared = (std::size_t{data[0]} << 8 | data[1]);
  std::vector<unsigned char> out(declared);
  (void)knnocc::io::detail::lzf_decompress(data + 2, size - 2, out.data(), out.size());
  // Round trip.
  const std::vector<unsigned char> packed = knnocc::io::detail::lzf_compress(data, size);
  std::vector<unsigned char> back(size);
  const std::string err =
      knnocc::io::detail::lzf_decompress(packed.data(), packed.size(), back.data(), back.size());
  if (!err.empty() || std::memcmp(back.data(), data, size) != 0) std::abort();
  return 0;
}
