#pragma once
// Shared helpers for the test suite: locating the real datasets (skipped when absent) and a
// deterministic random generator.

#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/xyz.hpp>

namespace knnocc::test {

/// ../shared/data beside the project root, or "" when the folder is absent.
inline std::string data_dir() {
#ifdef KNNOCC_SOURCE_DIR
  const std::filesystem::path p =
      std::filesystem::path(KNNOCC_SOURCE_DIR) / ".." / "shared" / "data";
  if (std::filesystem::is_directory(p)) return p.lexically_normal().string();
#endif
  return {};
}

/// A data file or folder under data_dir(), or "" when it (or the data folder) is missing.
inline std::string data_path(const std::string& relative) {
  const std::string d = data_dir();
  if (d.empty()) return {};
  const std::filesystem::path p = std::filesystem::path(d) / relative;
  return std::filesystem::exists(p) ? p.string() : std::string{};
}

/// scan.dat decompressed by the ctest fixture into the build tree, or "" when absent.
inline std::string scan_dat_path() {
#ifdef KNNOCC_BINARY_DIR
  const std::filesystem::path p = std::filesystem::path(KNNOCC_BINARY_DIR) / "data" / "scan.dat";
  if (std::filesystem::exists(p)) return p.string();
#endif
  return {};
}

/// scan.dat's points (88,206), or empty after a MESSAGE saying why the test is skipped (the data
/// folder or the ctest fixture that decompresses it is missing).
inline std::vector<Point3f> scan_dat_points_or_skip() {
  const std::string path = scan_dat_path();
  if (path.empty()) {
    MESSAGE("skipped: scan.dat not available (needs ../shared/data and the ctest fixture)");
    return {};
  }
  return io::read_xyz(path).points;
}

/// Scratch folder for files a test writes (inside the build tree when known).
inline std::filesystem::path scratch_dir(const std::string& name) {
#ifdef KNNOCC_BINARY_DIR
  std::filesystem::path p = std::filesystem::path(KNNOCC_BINARY_DIR) / "test_scratch" / name;
#else
  std::filesystem::path p = std::filesystem::temp_directory_path() / "knnocc_test" / name;
#endif
  std::filesystem::create_directories(p);
  return p;
}

using Rng = std::mt19937_64;

/// Largest single operator-new request since the last reset (tests/test_alloc.cpp replaces the
/// global operator new of the test executable).
std::size_t largest_allocation();
void reset_largest_allocation();

}  // namespace knnocc::test
