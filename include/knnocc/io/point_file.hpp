// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// read_points(): load a point file, choosing the reader by extension (case-insensitive).
//   .ply                -> read_ply
//   .pcd                -> read_pcd (ascii, binary, binary_compressed)
//   .bin                -> read_kitti_bin (KITTI velodyne scans)
//   .xyz / .dat / .txt  -> read_xyz (ASCII "x y z" per line; OctoMap .dat scans included)
//   .bz2                -> io::Error asking the user to decompress first
//   anything else       -> io::Error listing the supported extensions

#include <cctype>
#include <filesystem>
#include <string>

#include "cloud.hpp"
#include "error.hpp"
#include "kitti.hpp"
#include "pcd.hpp"
#include "ply.hpp"
#include "xyz.hpp"

namespace knnocc::io {

inline Cloud read_points(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply") return read_ply(path);
  if (ext == ".pcd") return read_pcd(path);
  if (ext == ".bin") return read_kitti_bin(path);
  if (ext == ".xyz" || ext == ".dat" || ext == ".txt") return read_xyz(path);
  if (ext == ".bz2") {
    throw Error(path, "compressed input: decompress first, e.g. bzip2 -dk FILE");
  }
  throw Error(path, "unknown point-file extension '" + ext +
                        "' (expected .ply, .pcd, .bin, .xyz, .dat or .txt)");
}

}  // namespace knnocc::io
