// The LZF codec of binary_compressed PCD (io/detail/lzf.hpp).
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/detail/lzf.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/point_file.hpp>

#include "test_support.hpp"

namespace io = knnocc::io;
using knnocc::Point3f;

using knnocc::test::append_le;
using knnocc::test::write_file;

namespace {

std::string decode(const std::vector<unsigned char>& in, std::size_t n, std::string& problem) {
  std::string out(n, '\0');
  problem = io::detail::lzf_decompress(in.data(), in.size(),
                                       reinterpret_cast<unsigned char*>(&out[0]), n);
  return out;
}

}  // namespace

TEST_CASE("lzf.hand-built stream decodes as the format says") {
  // literal "abcd", then a reference of 12 bytes at distance 4 (length 12 -> 7 + 3),
  // literal "xy", then a 4-byte reference at distance 2 (overlapping copy).
  const std::vector<unsigned char> in = {0x03, 'a',  'b', 'c', 'd',  0xE0, 0x03,
                                         0x03, 0x01, 'x', 'y', 0x40, 0x01};
  std::string problem;
  CHECK(decode(in, 22, problem) == "abcdabcdabcdabcdxyxyxy");
  CHECK(problem.empty());
  decode(in, 21, problem);
  CHECK(problem.find("more bytes than declared") != std::string::npos);
  decode(in, 23, problem);
  CHECK(problem.find("decodes to 22 bytes") != std::string::npos);
  decode({0x20, 0x05}, 3, problem);  // a reference before anything was written
  CHECK(problem.find("before the start") != std::string::npos);
  decode({0x05, 'a', 'b'}, 6, problem);  // literal run cut off
  CHECK(problem.find("past the end") != std::string::npos);
  decode({0x00, 'a', 0xE0}, 10, problem);  // long reference cut off
  CHECK(problem.find("cut off") != std::string::npos);
}

TEST_CASE("lzf.compress then decompress is the identity") {
  knnocc::test::Rng rng(11);
  std::vector<std::vector<unsigned char>> inputs = {{}, {7}, {1, 2}, {1, 2, 3}};
  std::vector<unsigned char> runs(100000, 0x55);  // long runs: references of 264 bytes
  inputs.push_back(runs);
  std::vector<unsigned char> noise(50000);
  for (auto& b : noise) b = static_cast<unsigned char>(rng());
  inputs.push_back(noise);
  std::vector<unsigned char> far(30000);  // repeats at distances around the 8192 limit
  for (std::size_t i = 0; i < far.size(); ++i)
    far[i] = i < 8190 ? static_cast<unsigned char>(rng()) : far[i - 8190 - (i % 5)];
  inputs.push_back(far);
  std::vector<unsigned char> floats(4 * 30000);  // float coordinates of a smooth surface
  for (std::size_t i = 0; i < 30000; ++i) {
    const float v = std::floor(static_cast<float>(i) / 7.0f) * 0.05f;
    std::memcpy(&floats[4 * i], &v, 4);
  }
  inputs.push_back(floats);
  for (const auto& in : inputs) {
    CAPTURE(in.size());
    const auto packed = io::detail::lzf_compress(in.data(), in.size());
    std::vector<unsigned char> out(in.size());
    CHECK(io::detail::lzf_decompress(packed.data(), packed.size(), out.data(), out.size()) == "");
    CHECK(out == in);
    CHECK(in.size() <= packed.size() * io::detail::kLzfMaxRatio);
  }
  CHECK(io::detail::lzf_compress(runs.data(), runs.size()).size() < 1500);
}

TEST_CASE("lzf.check and decoding in pieces agree with decoding into one buffer") {
  knnocc::test::Rng rng(5);
  std::vector<unsigned char> in(200000);  // runs, noise and far repeats: every kind of run
  for (std::size_t i = 0; i < in.size(); ++i) {
    const std::size_t kind = (i / 1000) % 3;
    in[i] = kind == 0   ? static_cast<unsigned char>(i / 300)
            : kind == 1 ? static_cast<unsigned char>(rng())
                        : (i >= 8192 ? in[i - 8192 + (i % 3)] : 0);
  }
  const auto packed = io::detail::lzf_compress(in.data(), in.size());
  CHECK(io::detail::lzf_check(packed.data(), packed.size(), in.size()) == "");
  for (const std::size_t piece : {std::size_t{1}, std::size_t{300}, std::size_t{5000},
                                  std::size_t{1} << 16, std::size_t{1} << 20}) {
    CAPTURE(piece);
    std::vector<unsigned char> out;
    std::size_t calls = 0;
    io::detail::LzfPieces pieces(
        [&](std::uint64_t offset, const unsigned char* data, std::size_t n) {
          CHECK(offset == out.size());  // in order, each byte once
          CHECK(n > 0);
          out.insert(out.end(), data, data + n);
          ++calls;
        },
        piece);
    REQUIRE(io::detail::lzf_decode(packed.data(), packed.size(), in.size(), pieces) == "");
    pieces.finish();
    CHECK(out == in);
    CHECK(calls >= in.size() / (piece + 8192 + 264));
  }
  // Damaged streams: the check finds what decoding finds, without producing anything.
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<unsigned char> bad = packed;
    bad.resize(rng() % 2 ? bad.size() : rng() % bad.size());
    for (int k = 0; k < 3; ++k) bad[rng() % bad.size()] = static_cast<unsigned char>(rng());
    const std::size_t declared = rng() % 2 ? in.size() : rng() % (2 * in.size());
    std::vector<unsigned char> out(declared);
    CHECK(io::detail::lzf_check(bad.data(), bad.size(), declared) ==
          io::detail::lzf_decompress(bad.data(), bad.size(), out.data(), out.size()));
  }
}
