// SPDX-License-Identifier: BSD-3-Clause
// SHA-256 (io/detail/sha256.hpp): FIPS 180-4's test messages, messages fed in pieces of every
// size, and the SHA extensions' rounds (where the CPU has them) against the portable ones.

#include <doctest/doctest.h>

#include <random>
#include <string>

#include <knnocc/io/detail/sha256.hpp>

using knnocc::io::detail::Sha256;

namespace {
std::string digest(const std::string& m, bool simd) {
  Sha256 h(simd);
  h.update(m);
  return h.hex();
}
}  // namespace

TEST_CASE("sha256: FIPS 180-4's messages, with and without the SHA extensions") {
  for (const bool simd : {true, false}) {
    CAPTURE(simd);
    CHECK(digest("", simd) == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
    CHECK(digest("abc", simd) ==
          "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
    CHECK(digest("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq", simd) ==
          "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
    CHECK(digest(std::string(1000000, 'a'), simd) ==
          "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  }
}

TEST_CASE("sha256: a message fed in pieces of any size is hashed as one") {
  std::mt19937 rng(7);
  for (const std::size_t n : {0, 1, 55, 56, 63, 64, 65, 127, 128, 129, 1000, 70001}) {
    std::string m(n, '\0');
    for (char& c : m) c = static_cast<char>(rng());
    const std::string whole = digest(m, false);
    for (const bool simd : {true, false}) {
      Sha256 h(simd);
      for (std::size_t at = 0; at < n;) {
        const std::size_t k = std::min<std::size_t>(n - at, rng() % 200);
        h.update(m.data() + at, k);
        at += k;
      }
      CHECK(h.hex() == whole);
    }
  }
}
