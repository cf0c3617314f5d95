// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A SLAM run's pose corrections: a folder of snapshots after_N.txt, each the trajectory of
// keyframes 0..N (the format of poses.txt, one line per keyframe in keyframe order) as the SLAM
// system knew it after keyframe N (`knnocc map --corrections DIR`, docs/live_mapping.md).
//
// Names, one rule: a snapshot is named after_N.txt, N the keyframe index in 1 to 9 decimal
// digits (leading zeros allowed), all in lower case. Any other name that looks like one (begins
// with "after" or ends in ".txt", in any case: AFTER_12.txt, after_12.TXT, after12.txt,
// notes.txt) is an error, as are two names of one keyframe (after_19.txt and after_000019.txt);
// names beginning with '.' and other files are ignored.
// Rows are checked against the keyframes: a snapshot after keyframe N holds exactly N + 1 rows
// (reading stops at the first extra row, so a huge file costs nothing), and row j's stamp is
// keyframe j's stamp in poses.txt within kSnapshotStampTolerance (rows reversed, shifted or of
// another run are refused naming the line). KITTI-format files have no stamps (stamp = row
// index): a KITTI snapshot goes with a KITTI poses.txt.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "error.hpp"
#include "trajectory.hpp"

namespace knnocc::io {

/// Largest difference, in seconds, between a snapshot row's stamp and its keyframe's stamp in
/// poses.txt: 0.1 ms, above the rounding of stamps written with 6 decimals (TUM, ORB-SLAM) and
/// far below the time between two keyframes.
inline constexpr double kSnapshotStampTolerance = 1e-4;

enum class SnapshotName {
  snapshot,  ///< after_N.txt
  other,     ///< not a snapshot, ignored
  bad,       ///< looks like a snapshot but breaks the rule: an error
};

/// Classifies a file name by the rule above; `keyframe` gets N for a snapshot.
inline SnapshotName classify_snapshot_name(const std::string& name, std::size_t& keyframe) {
  if (name.empty() || name[0] == '.') return SnapshotName::other;
  std::string lower = name;
  for (char& c : lower)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  const bool txt = lower.size() >= 4 && lower.compare(lower.size() - 4, 4, ".txt") == 0;
  if (lower.rfind("after", 0) != 0 && !txt) return SnapshotName::other;
  if (name.size() < 11 || name.rfind("after_", 0) != 0 ||
      name.compare(name.size() - 4, 4, ".txt") != 0)
    return SnapshotName::bad;
  const std::string digits = name.substr(6, name.size() - 10);
  if (digits.size() > 9 ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return SnapshotName::bad;
  keyframe = static_cast<std::size_t>(std::stoul(digits));
  return SnapshotName::snapshot;
}

/// The snapshots of `dir` by keyframe index, checked against `keyframes` (poses.txt: their
/// count and stamps); io::Error naming the file (and line) for anything the rules above refuse.
inline std::map<std::size_t, std::vector<Pose>> read_corrections(
    const std::string& dir, const std::vector<Pose>& keyframes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw Error(dir, "not a folder of after_N.txt snapshots");
  std::vector<fs::path> entries;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    entries.push_back(it->path());
  if (ec) throw Error(dir, "cannot list folder: " + ec.message());
  std::sort(entries.begin(), entries.end());  // the same message whatever the listing order

  std::map<std::size_t, std::pair<fs::path, std::vector<Pose>>> found;
  for (const fs::path& path : entries) {
    const std::string file = path.string();
    std::size_t after = 0;
    const SnapshotName kind = classify_snapshot_name(path.filename().string(), after);
    if (kind == SnapshotName::other) continue;
    if (kind == SnapshotName::bad)
      throw Error(file,
                  "not a snapshot name: snapshots are after_N.txt (N: the keyframe index, 1 to 9 "
                  "digits, lower case); nothing else here may begin with 'after' or end in .txt");
    if (fs::is_directory(path, ec)) throw Error(file, "is a folder, not a snapshot");
    const auto twin = found.find(after);
    if (twin != found.end())
      throw Error(file, "a second snapshot of keyframe " + std::to_string(after) + " (also " +
                            twin->second.first.filename().string() + ")");
    if (after >= keyframes.size())
      throw Error(file, "keyframe " + std::to_string(after) + " does not exist (the sequence has " +
                            std::to_string(keyframes.size()) + ")");
    std::vector<std::size_t> lines;
    std::vector<Pose> poses = read_trajectory(file, after + 1, &lines);
    if (poses.size() != after + 1)
      throw Error(file, "expected " + std::to_string(after + 1) + " poses (keyframes 0.." +
                            std::to_string(after) + "), found " + std::to_string(poses.size()));
    for (std::size_t j = 0; j < poses.size(); ++j) {
      if (std::abs(poses[j].stamp - keyframes[j].stamp) <= kSnapshotStampTolerance) continue;
      char text[200];
      std::snprintf(text, sizeof text,
                    "line %zu: stamp %.6f is not keyframe %zu's (%.6f in poses.txt; tolerance "
                    "1e-4 s): rows must be keyframes 0..%zu in order",
                    lines[j], poses[j].stamp, j, keyframes[j].stamp, after);
      throw Error(file, text);
    }
    found.emplace(after, std::make_pair(path, std::move(poses)));
  }
  std::map<std::size_t, std::vector<Pose>> out;
  for (auto& [after, snapshot] : found) out.emplace(after, std::move(snapshot.second));
  return out;
}

}  // namespace knnocc::io
