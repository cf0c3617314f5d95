#pragma once
// Shared helpers for the test suite: locating the real datasets (skipped when absent), scratch
// files, byte strings, voxel values and a deterministic random generator. One definition each:
// the sanitizer build compiles the test sources in unity batches, where file-local twins clash.

#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/detail/bytes.hpp>
#include <knnocc/io/xyz.hpp>

namespace knnocc::test {

/// Marks the running test case as skipped for ctest (SKIP_REGULAR_EXPRESSION in
/// tests/CMakeLists.txt) and says why; the caller returns right after. A test that cannot run
/// (missing data, missing liboctomap, a CPU without the instructions it tests) reports SKIPPED,
/// never PASSED.
inline void skip(const std::string& why) {
  std::printf("KNNOCC_SKIPPED: %s\n", why.c_str());
  std::fflush(stdout);
}

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

/// scan.dat's points (88,206), or empty after skip() says why the test cannot run (the data
/// folder or the ctest fixture that decompresses it is missing).
inline std::vector<Point3f> scan_dat_points_or_skip() {
  const std::string path = scan_dat_path();
  if (path.empty()) {
    knnocc::test::skip(
        "skipped: scan.dat not available (needs ../shared/data and the ctest fixture)");
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

/// A file named `name` in scratch_dir(folder).
inline std::string scratch_file(const std::string& folder, const std::string& name) {
  return (scratch_dir(folder) / name).string();
}

/// The whole file as bytes ("" when it cannot be opened).
inline std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// Writes bytes to path, replacing the file.
inline void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Whether a temporary of `target` ("<name>.tmp-XXXXXX", io::AtomicFile) is left beside it.
inline bool has_temporary_beside(const std::filesystem::path& target) {
  const std::string prefix = target.filename().string() + ".tmp";
  std::filesystem::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().filename().string().rfind(prefix, 0) == 0) return true;
  return false;
}

/// Appends v to s little-endian, on every host.
template <class T>
void append_le(std::string& s, T v) {
  char b[sizeof(T)];
  io::detail::store_le(b, v);
  s.append(b, sizeof(T));
}

/// Every known voxel of an OccupancyMap: packed key -> log-odds, ordered.
template <class Map>
std::map<std::uint64_t, float> voxel_values(const Map& map) {
  std::map<std::uint64_t, float> out;
  map.for_each_voxel([&](const auto& k, float v) { out[k.pack()] = v; });
  return out;
}

/// A sensor origin and the end points of its rays (world frame).
struct Scan {
  Point3f origin;
  std::vector<Point3f> points;
};

using Rng = std::mt19937_64;

}  // namespace knnocc::test
