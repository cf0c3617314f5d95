// Pose snapshots of a SLAM run (io/corrections.hpp): the one name rule, duplicates, rows checked
// against the keyframes' count and stamps, a huge snapshot refused at its first extra row.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include <knnocc/io/corrections.hpp>

#include "io_files.hpp"
#include "test_support.hpp"

using namespace knnocc::test::io_files;  // io, fs, file helpers

namespace {

// Keyframes 0..n-1 with stamps 100.25 + 0.5 i (as poses.txt gives them).
std::vector<io::Pose> keyframes(std::size_t n) {
  std::vector<io::Pose> k(n);
  for (std::size_t i = 0; i < n; ++i) {
    k[i].stamp = 100.25 + 0.5 * double(i);
    k[i].t = Eigen::Vector3d(double(i), 0, 0);
  }
  return k;
}

// The rows of a snapshot after keyframe `after`, stamps shifted by `shift` (TUM, %.6f).
std::string rows(std::size_t after, double shift = 0.0) {
  std::string s = "# stamp tx ty tz qx qy qz qw\n";
  for (std::size_t j = 0; j <= after; ++j) {
    char line[96];
    std::snprintf(line, sizeof line, "%.6f %zu.5 0 0 0 0 0 1\n", 100.25 + 0.5 * double(j) + shift,
                  j);
    s += line;
  }
  return s;
}

}  // namespace

TEST_CASE("corrections.one rule for snapshot names") {
  auto kind = [](const std::string& name, std::size_t expect_keyframe = 0) {
    std::size_t k = 12345;
    const io::SnapshotName c = io::classify_snapshot_name(name, k);
    if (c == io::SnapshotName::snapshot) CHECK(k == expect_keyframe);
    return c;
  };
  using io::SnapshotName;
  CHECK(kind("after_000019.txt", 19) == SnapshotName::snapshot);
  CHECK(kind("after_19.txt", 19) == SnapshotName::snapshot);
  CHECK(kind("after_0.txt", 0) == SnapshotName::snapshot);
  CHECK(kind("after_123456789.txt", 123456789) == SnapshotName::snapshot);
  for (const char* bad :
       {"AFTER_000019.txt", "after_000019.TXT", "After_1.txt", "after19.txt", "after_.txt",
        "after_abc.txt", "after_1234567890.txt", "after_-1.txt", "after_1.txt.bak",
        "after_1.txt.tmp-a1B2c3", "afterwards", "notes.txt", "19.txt", "snapshot_19.TXT"}) {
    CAPTURE(bad);
    CHECK(kind(bad) == SnapshotName::bad);
  }
  for (const char* other : {"README", "poses.csv", ".after_1.txt.swp", ".DS_Store", "log"}) {
    CAPTURE(other);
    CHECK(kind(other) == SnapshotName::other);
  }
}

TEST_CASE("corrections.snapshots are read and checked against the keyframes") {
  ScratchDir dir("corrections");
  const auto k = keyframes(12);
  auto folder = [&](const std::string& name) {
    const fs::path d = dir.path() / name;
    fs::create_directories(d);
    return d;
  };
  auto refused = [&](const fs::path& d, const std::string& file, const std::string& expect) {
    const std::string msg = error_of([&] { io::read_corrections(d.string(), k); });
    CAPTURE(msg);
    CHECK(contains(msg, (d / file).string() + ": " + expect));
  };

  const fs::path good = folder("good");
  write_bytes((good / "after_000004.txt").string(), rows(4));
  write_bytes((good / "after_11.txt").string(), rows(11, 5e-5));  // within the tolerance
  write_bytes((good / "README").string(), "not a snapshot\n");
  const auto c = io::read_corrections(good.string(), k);
  REQUIRE(c.size() == 2);
  CHECK(c.at(4).size() == 5);
  CHECK(c.at(11).size() == 12);
  CHECK(c.at(11)[3].t.x() == 3.5);

  const fs::path twin = folder("twin");
  write_bytes((twin / "after_000004.txt").string(), rows(4));
  write_bytes((twin / "after_4.txt").string(), rows(4));
  refused(twin, "after_4.txt", "a second snapshot of keyframe 4 (also after_000004.txt)");

  const fs::path upper = folder("upper");
  write_bytes((upper / "AFTER_000004.txt").string(), rows(4));
  refused(upper, "AFTER_000004.txt", "not a snapshot name: snapshots are after_N.txt");

  const fs::path shifted = folder("shifted");
  write_bytes((shifted / "after_000004.txt").string(), rows(4, 0.5));  // each row a keyframe late
  refused(shifted, "after_000004.txt",
          "line 2: stamp 100.750000 is not keyframe 0's (100.250000 in poses.txt; tolerance 1e-4 "
          "s): rows must be keyframes 0..4 in order");
  write_bytes((shifted / "after_000004.txt").string(), rows(4, 2e-4));  // beyond the tolerance
  refused(shifted, "after_000004.txt", "line 2: stamp 100.250200 is not keyframe 0's");

  const fs::path reversed = folder("reversed");
  std::string r = "100.25 0 0 0 0 0 0 1\n";
  for (int j = 1; j <= 2; ++j) r = std::to_string(100.25 + 0.5 * j) + " 0 0 0 0 0 0 1\n" + r;
  write_bytes((reversed / "after_000002.txt").string(), r);
  refused(reversed, "after_000002.txt", "line 1: stamp 101.250000 is not keyframe 0's");

  const fs::path counts = folder("counts");
  write_bytes((counts / "after_000004.txt").string(), rows(3));
  refused(counts, "after_000004.txt", "expected 5 poses (keyframes 0..4), found 4");
  write_bytes((counts / "after_000004.txt").string(), rows(4) + rows(30).substr(rows(4).size()));
  refused(counts, "after_000004.txt", "line 7: more poses than the 5 expected");
  write_bytes((counts / "after_000004.txt").string(), rows(4));
  write_bytes((counts / "after_000012.txt").string(), rows(12));
  refused(counts, "after_000012.txt", "keyframe 12 does not exist (the sequence has 12)");

  const std::string missing = (dir.path() / "missing").string();
  CHECK(contains(error_of([&] { io::read_corrections(missing, k); }),
                 missing + ": not a folder of after_N.txt snapshots"));
}
