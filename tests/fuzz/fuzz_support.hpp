#pragma once
// libFuzzer harness support: the readers take paths, so each input is written to a scratch file
// first. A reader may reject an input only with knnocc::io::Error; any other exception escapes
// and libFuzzer reports it as a crash, like a sanitizer finding.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <knnocc/io/error.hpp>

namespace knnocc::fuzz {

/// Writes the input to a per-process file with the given extension and returns its path.
inline std::string input_file(const std::uint8_t* data, std::size_t size, const char* extension) {
  const char* dir = std::getenv("TMPDIR");
  const std::string path = std::string(dir && *dir ? dir : "/tmp") + "/knnocc_fuzz_" +
                           std::to_string(::getpid()) + extension;
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return path;
}

/// Runs read(path) on the input; io::Error is the one accepted way to refuse it.
template <class Read>
void read_rejecting_cleanly(const std::uint8_t* data, std::size_t size, const char* extension,
                            Read read) {
  const std::string path = input_file(data, size, extension);
  try {
    read(path);
  } catch (const io::Error&) {
  }
}

}  // namespace knnocc::fuzz
