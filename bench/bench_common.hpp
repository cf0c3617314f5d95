#pragma once
// What every bench program shares: a monotonic clock in seconds and the scan.dat dataset.

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace knnocc::bench {

inline double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// scan.dat ships bz2-compressed; decompress once into build/data (as the test fixture does).
// Returns its path, or "" when the data folder or bzip2 is missing.
inline std::string scan_dat(const std::filesystem::path& data) {
  namespace fs = std::filesystem;
  const fs::path bz2 = data / "octomap_fr079" / "scan.dat.bz2";
  const fs::path out = fs::path("build") / "data" / "scan.dat";
  if (fs::exists(out)) return out.string();
  if (!fs::exists(bz2)) return {};
  fs::create_directories(out.parent_path());
  const std::string tmp = out.string() + ".tmp";
  const std::string cmd = "bzip2 -dc '" + bz2.string() + "' > '" + tmp + "'";
  if (std::system(cmd.c_str()) != 0) return {};
  fs::rename(tmp, out);
  return out.string();
}

}  // namespace knnocc::bench
