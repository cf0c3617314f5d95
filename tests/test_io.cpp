// Tests for knnocc/io: PLY, xyz, poses, sequence folders, point-file dispatch, voxel lists.
// Files are written under the build tree (test_support.hpp's scratch_dir) and removed afterwards.
// The real-data cases need ../shared/data (located via KNNOCC_SOURCE_DIR) and skip without it.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <knnocc/io/cloud.hpp>
#include <knnocc/io/error.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/point_file.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>
#include <knnocc/io/voxel_list.hpp>
#include <knnocc/io/xyz.hpp>

#include "test_support.hpp"

namespace io = knnocc::io;
namespace fs = std::filesystem;
using knnocc::Point3f;

namespace {

// A fresh directory per test case, unique per process so parallel runs (two compilers, ctest -j)
// never share files; removed on scope exit.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& name) {
    std::random_device rd;
    path_ = knnocc::test::scratch_dir("io") / (name + "_" + std::to_string(rd()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  REQUIRE(f.good());
}

std::string read_text(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

bool host_little() {
  const std::uint16_t one = 1;
  unsigned char b = 0;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

// Appends v in the requested byte order.
template <class T>
void put(std::string& s, T v, bool big_endian) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian == host_little()) std::reverse(b, b + sizeof(T));
  s.append(reinterpret_cast<const char*>(b), sizeof(T));
}

// Runs f and returns the io::Error message ("" if none was thrown).
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const io::Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("<not io::Error> ") + e.what();
  }
  return "<no exception>";
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// Writes `bytes` to a fresh file and checks read_ply throws io::Error naming the file and
// mentioning `expect`.
void check_ply_error(const ScratchDir& dir, const std::string& name, const std::string& bytes,
                     const std::string& expect) {
  const std::string p = dir.file(name);
  write_bytes(p, bytes);
  CAPTURE(name);
  CHECK_THROWS_AS(io::read_ply(p), io::Error);
  const std::string msg = error_of([&] { io::read_ply(p); });
  CAPTURE(msg);
  CHECK(contains(msg, p));
  CHECK(contains(msg, expect));
}

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

std::vector<Point3f> sample_points() {
  std::vector<Point3f> pts;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  for (int i = 0; i < 1000; ++i) pts.push_back(Point3f{u(rng), u(rng), u(rng)});
  pts.push_back(Point3f{0.0f, -0.0f, 1e-30f});
  pts.push_back(Point3f{std::numeric_limits<float>::max(), std::numeric_limits<float>::lowest(),
                        std::numeric_limits<float>::denorm_min()});
  return pts;
}

}  // namespace

TEST_CASE("io.error carries file and problem") {
  const io::Error e("a/b.ply", "something broke");
  CHECK(std::string(e.what()) == "a/b.ply: something broke");
  CHECK(e.file() == "a/b.ply");
  CHECK(e.problem() == "something broke");
  const std::runtime_error& base = e;
  CHECK(std::string(base.what()) == "a/b.ply: something broke");
}

TEST_CASE("io.ply binary round trip") {
  ScratchDir dir("ply_roundtrip");
  const std::vector<Point3f> pts = sample_points();

  SUBCASE("without ids") {
    const std::string p = dir.file("cloud.ply");
    io::write_ply(p, pts);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids.empty());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      CHECK(same_bits(c.points[i].x, pts[i].x));
      CHECK(same_bits(c.points[i].y, pts[i].y));
      CHECK(same_bits(c.points[i].z, pts[i].z));
    }
    CHECK(fs::file_size(p) == read_text(p).find("end_header\n") + 11 + 12 * pts.size());
    CHECK_FALSE(fs::exists(p + ".tmp"));
  }
  SUBCASE("with ids") {
    std::vector<std::uint64_t> ids;
    for (std::size_t i = 0; i < pts.size(); ++i) ids.push_back(4000000000ull - i * 3);
    const std::string p = dir.file("cloud_ids.ply");
    io::write_ply(p, pts, &ids);
    CHECK(contains(read_text(p), "property uint id\n"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids == ids);
    for (std::size_t i = 0; i < pts.size(); ++i) CHECK(same_bits(c.points[i].y, pts[i].y));
  }
  SUBCASE("ascii writer") {
    std::vector<std::uint64_t> ids(pts.size(), 17);
    const std::string p = dir.file("cloud_ascii.ply");
    io::write_ply(p, pts, &ids, /*binary=*/false);
    CHECK(contains(read_text(p), "format ascii 1.0\n"));
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == pts.size());
    CHECK(c.ids == ids);
    for (std::size_t i = 0; i < pts.size(); ++i) CHECK(same_bits(c.points[i].z, pts[i].z));
  }
  SUBCASE("empty cloud") {
    const std::string p = dir.file("empty.ply");
    io::write_ply(p, {});
    CHECK(io::read_ply(p).points.empty());
  }
  SUBCASE("non-finite values survive") {
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<Point3f> odd = {{std::nanf(""), inf, -inf}, {1.0f, 2.0f, 3.0f}};
    const std::string p = dir.file("odd.ply");
    io::write_ply(p, odd);
    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 2);
    CHECK(std::isnan(c.points[0].x));
    CHECK(c.points[0].y == inf);
    CHECK(c.points[0].z == -inf);
    CHECK(c.points[1].z == 3.0f);
  }
  SUBCASE("writer errors") {
    std::vector<std::uint64_t> short_ids(3, 1);
    const std::string p = dir.file("bad.ply");
    CHECK_THROWS_AS(io::write_ply(p, pts, &short_ids), io::Error);
    std::vector<std::uint64_t> big_ids(pts.size(), 1ull << 40);
    CHECK(contains(error_of([&] { io::write_ply(p, pts, &big_ids); }), "does not fit"));
    CHECK_FALSE(fs::exists(p));

    const std::string missing = dir.file("no/such/dir/x.ply");
    const std::string msg = error_of([&] { io::write_ply(missing, pts); });
    CHECK(contains(msg, missing));
    CHECK(contains(msg, "cannot create temporary file"));
  }
  SUBCASE("overwrite replaces atomically") {
    const std::string p = dir.file("over.ply");
    io::write_ply(p, pts);
    io::write_ply(p, {Point3f{1, 2, 3}});
    CHECK(io::read_ply(p).points.size() == 1);
    CHECK_FALSE(fs::exists(p + ".tmp"));
  }
}

TEST_CASE("io.ply ascii with extra properties, comments, CRLF header and a face element") {
  ScratchDir dir("ply_ascii");
  const std::string p = dir.file("ascii.ply");
  write_bytes(p,
              "ply\r\n"
              "format ascii 1.0\r\n"
              "comment made by hand\r\n"
              "obj_info anything at all\r\n"
              "element vertex 3\r\n"
              "property double x\r\n"
              "property uchar red\r\n"
              "property double y\r\n"
              "property uchar green\r\n"
              "property uchar blue\r\n"
              "property float64 z\r\n"
              "property float intensity\r\n"
              "property int32 id\r\n"
              "element face 2\r\n"
              "property list uchar int vertex_indices\r\n"
              "end_header\r\n"
              "1.5 255 -2.25 0 7 1e2 0.5 42\r\n"
              "  +3\t1 4 2 3 -0.125 9 7\n"
              "nan 0 inf 0 0 -inf 1 0\n"
              "3 0 1 2\n"
              "3 0 2 1\n");
  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 3);
  CHECK(c.points[0].x == 1.5f);
  CHECK(c.points[0].y == -2.25f);
  CHECK(c.points[0].z == 100.0f);
  CHECK(c.points[1].x == 3.0f);
  CHECK(c.points[1].y == 4.0f);
  CHECK(c.points[1].z == -0.125f);
  // NaN/Inf are data, not errors: the mapping layer skips them.
  CHECK(std::isnan(c.points[2].x));
  CHECK(std::isinf(c.points[2].y));
  CHECK(c.points[2].z == -std::numeric_limits<float>::infinity());
  CHECK(c.ids == std::vector<std::uint64_t>{42, 7, 0});
}

TEST_CASE("io.ply ascii element before vertex is skipped") {
  ScratchDir dir("ply_ascii_before");
  const std::string p = dir.file("before.ply");
  write_bytes(p,
              "ply\nformat ascii 1.0\n"
              "element face 2\nproperty list uchar int vertex_indices\nproperty uchar flag\n"
              "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n"
              "3 0 1 2 1\n4 0 1 2 3 0\n"
              "1 2 3\n4 5 6\n");
  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[1].x == 4.0f);
  CHECK(c.points[1].z == 6.0f);
}

TEST_CASE("io.ply big-endian hand-crafted bytes") {
  ScratchDir dir("ply_be");
  const std::string p = dir.file("be.ply");
  std::string bytes =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "element vertex 2\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property ushort id\n"
      "property uchar red\n"
      "element face 1\n"
      "property list uchar int vertex_indices\n"
      "end_header\n";
  // Vertex 0 spelled out byte by byte: 1.0f, -3.5f, 2.0f, id 258, red 9.
  const unsigned char v0[] = {0x3F, 0x80, 0x00, 0x00, 0xC0, 0x60, 0x00, 0x00,
                              0x40, 0x00, 0x00, 0x00, 0x01, 0x02, 0x09};
  bytes.append(reinterpret_cast<const char*>(v0), sizeof v0);
  put(bytes, 0.25f, true);
  put(bytes, 1e6f, true);
  put(bytes, -7.0f, true);
  put(bytes, std::uint16_t{65535}, true);
  put(bytes, std::uint8_t{1}, true);
  put(bytes, std::uint8_t{3}, true);  // face: 3 indices
  for (int k = 0; k < 3; ++k) put(bytes, std::int32_t{k}, true);
  write_bytes(p, bytes);

  const io::Cloud c = io::read_ply(p);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[0].x == 1.0f);
  CHECK(c.points[0].y == -3.5f);
  CHECK(c.points[0].z == 2.0f);
  CHECK(c.points[1].x == 0.25f);
  CHECK(c.points[1].y == 1e6f);
  CHECK(c.points[1].z == -7.0f);
  CHECK(c.ids == std::vector<std::uint64_t>{258, 65535});
}

TEST_CASE("io.ply binary doubles, extra properties and a scalar element before vertex") {
  ScratchDir dir("ply_le_double");
  for (const bool big : {false, true}) {
    CAPTURE(big);
    const std::string p = dir.file(big ? "be_double.ply" : "le_double.ply");
    std::string bytes = std::string("ply\nformat ") +
                        (big ? "binary_big_endian" : "binary_little_endian") +
                        " 1.0\n"
                        "element camera 2\nproperty float32 fx\nproperty int16 w\n"
                        "element vertex 3\n"
                        "property uint8 red\nproperty uint8 green\nproperty uint8 blue\n"
                        "property float64 x\nproperty double y\nproperty float64 z\n"
                        "property float intensity\nproperty int8 id\n"
                        "element face 1\nproperty list uchar uint vertex_indices\n"
                        "end_header\n";
    for (int k = 0; k < 2; ++k) {
      put(bytes, 525.0f, big);
      put(bytes, std::int16_t{640}, big);
    }
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) put(bytes, std::uint8_t{200}, big);
      put(bytes, 0.1 * i, big);
      put(bytes, -1.0 - i, big);
      put(bytes, 1e300, big);  // beyond float range: becomes +inf, not UB
      put(bytes, 0.75f, big);
      put(bytes, std::int8_t{static_cast<std::int8_t>(100 + i)}, big);
    }
    put(bytes, std::uint8_t{2}, big);
    put(bytes, std::uint32_t{0}, big);
    put(bytes, std::uint32_t{1}, big);
    write_bytes(p, bytes);

    const io::Cloud c = io::read_ply(p);
    REQUIRE(c.points.size() == 3);
    CHECK(c.points[2].x == static_cast<float>(0.2));
    CHECK(c.points[1].y == -2.0f);
    CHECK(c.points[0].z == std::numeric_limits<float>::infinity());
    CHECK(c.ids == std::vector<std::uint64_t>{100, 101, 102});
  }
}

TEST_CASE("io.ply malformed files throw io::Error naming the file") {
  ScratchDir dir("ply_bad");
  const std::string xyz_props = "property float x\nproperty float y\nproperty float z\n";

  SUBCASE("cannot open") {
    const std::string p = dir.file("missing.ply");
    CHECK_THROWS_AS(io::read_ply(p), io::Error);
    const std::string msg = error_of([&] { io::read_ply(p); });
    CHECK(contains(msg, p));
    CHECK(contains(msg, "cannot open"));
    const std::string d = dir.file("");
    CHECK(contains(error_of([&] { io::read_ply(d); }), "not a regular file"));
  }
  SUBCASE("not a PLY") {
    check_ply_error(dir, "notply.ply", "hello\nformat ascii 1.0\n", "not a PLY");
    check_ply_error(dir, "plyx.ply", "plyx\n", "not a PLY");
    check_ply_error(dir, "empty.ply", "", "not a PLY");
  }
  SUBCASE("format problems") {
    check_ply_error(dir, "noformat.ply", "ply\nelement vertex 0\n" + xyz_props + "end_header\n",
                    "no format line");
    check_ply_error(
        dir, "badformat.ply",
        "ply\nformat binary_middle_endian 1.0\nelement vertex 0\n" + xyz_props + "end_header\n",
        "unknown PLY format 'binary_middle_endian'");
    check_ply_error(dir, "noend.ply", "ply\nformat ascii 1.0\nelement vertex 0\n" + xyz_props,
                    "no end_header");
    check_ply_error(dir, "keyword.ply", "ply\nformat ascii 1.0\nelemnt vertex 0\nend_header\n",
                    "unknown PLY header keyword 'elemnt'");
    check_ply_error(dir, "badtype.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n",
                    "unknown PLY property type 'float128'");
    check_ply_error(dir, "badcount.ply",
                    "ply\nformat ascii 1.0\nelement vertex -5\n" + xyz_props + "end_header\n",
                    "invalid element count '-5'");
  }
  SUBCASE("vertex layout problems") {
    check_ply_error(dir, "novertex.ply", "ply\nformat ascii 1.0\nend_header\n",
                    "no 'vertex' element");
    check_ply_error(dir, "noy.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                    "property float z\nend_header\n1 2\n",
                    "no property 'y'");
    check_ply_error(dir, "intx.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\n"
                    "property float y\nproperty float z\nend_header\n1 2 3\n",
                    "'x' must be a float or double");
    check_ply_error(dir, "floatid.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props +
                        "property float id\nend_header\n1 2 3 4\n",
                    "'id' must be an integer");
  }
  SUBCASE("absurd vertex counts never allocate") {
    std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\n" +
                      xyz_props + "end_header\n";
    bin.append(100, '\0');  // 100 bytes of data behind a header claiming 24 GB
    check_ply_error(dir, "huge.ply", bin,
                    "file truncated: header claims 2000000000 vertices but only 100 bytes of "
                    "data");
    check_ply_error(
        dir, "huge_ascii.ply",
        "ply\nformat ascii 1.0\nelement vertex 2000000000\n" + xyz_props + "end_header\n1 2 3\n",
        "file truncated: header claims 2000000000 vertices");
    check_ply_error(dir, "huge_before.ply",
                    "ply\nformat binary_little_endian 1.0\nelement junk 18446744073709551615\n"
                    "property double a\nelement vertex 1\n" +
                        xyz_props + "end_header\n",
                    "file truncated: element 'junk'");
  }
  SUBCASE("truncated binary") {
    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + xyz_props + "end_header\n";
    for (int k = 0; k < 8; ++k) put(bin, 1.0f, false);  // 2 2/3 vertices
    check_ply_error(dir, "short.ply", bin,
                    "file truncated: header claims 3 vertices but only 32 bytes of data");
  }
  SUBCASE("ascii data problems") {
    check_ply_error(dir, "short_ascii.ply",
                    "ply\nformat ascii 1.0\nelement vertex 3\n" + xyz_props +
                        "end_header\n1.000 2.000 3.000\n4.000 5.000 6.000\n",
                    "truncated ascii data: header claims 3 vertex records but data ends in "
                    "record 2");
    check_ply_error(
        dir, "word.ply",
        "ply\nformat ascii 1.0\nelement vertex 2\n" + xyz_props + "end_header\n1 2 3\n4.0 abc 6\n",
        "line 9 (vertex 1): cannot parse 'abc' as a number");
    check_ply_error(
        dir, "glued.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props + "end_header\n1 2.5.1 3\n",
        "cannot parse '2.5.1'");
    check_ply_error(dir, "negid.ply",
                    "ply\nformat ascii 1.0\nelement vertex 1\n" + xyz_props +
                        "property int id\nend_header\n1 2 3 -4\n",
                    "negative id -4");
  }
  SUBCASE("binary list element before vertex is unsupported") {
    std::string bin =
        "ply\nformat binary_little_endian 1.0\nelement face 1\n"
        "property list uchar int vertex_indices\nelement vertex 1\n" +
        xyz_props + "end_header\n";
    bin.append(17, '\0');
    check_ply_error(dir, "facefirst.ply", bin, "unsupported binary PLY: element 'face'");
  }
}

TEST_CASE("io.xyz parsing") {
  ScratchDir dir("xyz");
  const std::string p = dir.file("points.xyz");
  write_bytes(p,
              "# a comment line\n"
              "1 2 3\n"
              "\n"
              "   \t\n"
              "  # indented comment\n"
              "-0.0434742 -4.82982 0.499645\r\n"
              "4\t5\t6 255 128 0 any text at all\n"
              "+1e-3 2E2 -inf\n"
              "7 8 9");  // no final newline
  const io::Cloud c = io::read_xyz(p);
  REQUIRE(c.points.size() == 5);
  CHECK(c.ids.empty());
  CHECK(c.points[0].x == 1.0f);
  CHECK(c.points[1].x == -0.0434742f);
  CHECK(c.points[1].z == 0.499645f);
  CHECK(c.points[2].z == 6.0f);
  CHECK(c.points[3].x == 1e-3f);
  CHECK(c.points[3].y == 200.0f);
  CHECK(c.points[3].z == -std::numeric_limits<float>::infinity());
  CHECK(c.points[4].z == 9.0f);

  SUBCASE("a short line reports its line number") {
    const std::string bad = dir.file("bad.xyz");
    write_bytes(bad, "1 2 3\n# c\n4 5 6\n7 8\n");
    CHECK_THROWS_AS(io::read_xyz(bad), io::Error);
    const std::string msg = error_of([&] { io::read_xyz(bad); });
    CHECK(contains(msg, bad));
    CHECK(contains(msg, "line 4: expected 3 numbers (x y z), found 2"));
  }
  SUBCASE("an unparsable number reports its line number") {
    const std::string bad = dir.file("word.xyz");
    write_bytes(bad, "1 2 3\n1 two 3\n");
    const std::string msg = error_of([&] { io::read_xyz(bad); });
    CHECK(contains(msg, bad));
    CHECK(contains(msg, "line 2: cannot parse 'two' as a number"));
  }
  SUBCASE("empty file gives an empty cloud") {
    const std::string e = dir.file("empty.xyz");
    write_bytes(e, "");
    CHECK(io::read_xyz(e).points.empty());
  }
}

TEST_CASE("io.poses parsing, quaternion order and transforms") {
  ScratchDir dir("poses");
  const double s = std::sqrt(0.5);
  const std::string p = dir.file("poses.txt");
  {
    std::ostringstream text;
    text.precision(17);
    text << "# stamp tx ty tz qx qy qz qw\n"
         << "10.5 1 2 3 0 0 0 1\n"
         << "\n"
         << "11.5 1 2 3 0 0 " << s << " " << s << "  # 90 deg about z\n"
         << "12.5 0 0 0 0 0 0 1.0005\n";  // slightly off: normalised
    write_bytes(p, text.str());
  }
  const std::vector<io::Pose> poses = io::read_poses(p);
  REQUIRE(poses.size() == 3);
  CHECK(poses[0].stamp == 10.5);
  CHECK(poses[0].t.isApprox(Eigen::Vector3d(1, 2, 3)));
  CHECK(poses[1].q.z() == doctest::Approx(s));
  CHECK(poses[1].q.w() == doctest::Approx(s));
  CHECK(poses[2].q.norm() == doctest::Approx(1.0).epsilon(1e-12));

  const Eigen::Vector3d moved = poses[1].transform() * Eigen::Vector3d(1, 0, 0);
  CHECK(moved.isApprox(Eigen::Vector3d(1, 3, 3), 1e-12));

  std::vector<Point3f> pts = {{1, 0, 0}, {0, 0, 5}};
  std::vector<Point3f> world;
  io::transform_to_world(poses[1], pts, world);
  REQUIRE(world.size() == 2);
  CHECK(world[0].x == doctest::Approx(1.0));
  CHECK(world[0].y == doctest::Approx(3.0));
  CHECK(world[1].z == doctest::Approx(8.0));
  io::transform_to_world(poses[1], pts, pts);  // in place is allowed
  CHECK(pts[1].z == doctest::Approx(8.0));

  const auto check_bad = [&](const std::string& name, const std::string& text,
                             const std::string& expect) {
    const std::string bad = dir.file(name);
    write_bytes(bad, text);
    CAPTURE(name);
    CHECK_THROWS_AS(io::read_poses(bad), io::Error);
    const std::string msg = error_of([&] { io::read_poses(bad); });
    CAPTURE(msg);
    CHECK(contains(msg, bad));
    CHECK(contains(msg, expect));
  };
  check_bad("norm.txt", "# h\n0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 0.87\n",
            "line 3: quaternion norm 0.87 is not 1");
  check_bad("wxyz.txt", "0 0 0 0 1 0 0 0.5\n", "line 1: quaternion norm");
  check_bad("nan.txt", "0 0 0 0 0 0 0 1\n1 nan 0 0 0 0 0 1\n", "line 2: non-finite");
  check_bad("inf.txt", "inf 0 0 0 0 0 0 1\n", "line 1: non-finite");
  check_bad("short.txt", "0 0 0 0 0 0 1\n", "line 1: expected 8 numbers");
  check_bad("long.txt", "0 0 0 0 0 0 0 1 5\n", "line 1: expected 8 numbers");
  check_bad("word.txt", "0 0 0 zero 0 0 0 1\n", "line 1: cannot parse 'zero'");
}

TEST_CASE("io.sequence folder") {
  ScratchDir dir("sequence");
  const fs::path root = dir.path() / "seq";
  fs::create_directories(root / "clouds");
  write_bytes((root / "poses.txt").string(),
              "# stamp tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n2 2 0 0 0 0 0 1\n");
  // Written out of order on purpose: open() must sort by name.
  for (const int i : {2, 0, 1}) {
    std::vector<Point3f> pts(static_cast<std::size_t>(i + 1), Point3f{float(i), 0, 0});
    char name[32];
    std::snprintf(name, sizeof name, "%06d.ply", i);
    io::write_ply((root / "clouds" / name).string(), pts);
  }
  write_bytes((root / "clouds" / "README.txt").string(), "not a cloud\n");

  CHECK(io::is_sequence_dir(root.string()));
  CHECK_FALSE(io::is_sequence_dir((root / "clouds").string()));
  CHECK_FALSE(io::is_sequence_dir(dir.file("nowhere")));

  const io::Sequence seq = io::Sequence::open(root.string());
  REQUIRE(seq.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(seq.pose(i).t.x() == double(i));
    CHECK(fs::path(seq.cloud_path(i)).filename().string().substr(0, 6) ==
          "00000" + std::to_string(i));
    const io::Cloud c = seq.load_cloud(i);
    REQUIRE(c.points.size() == i + 1);
    CHECK(c.points[0].x == float(i));
  }
  CHECK_THROWS_AS(seq.pose(3), io::Error);

  const auto open_error = [](const fs::path& d) {
    return error_of([&] { io::Sequence::open(d.string()); });
  };
  CHECK(contains(open_error(dir.path() / "nowhere"), "does not exist"));

  // One extra cloud: counts differ.
  io::write_ply((root / "clouds" / "000003.ply").string(), {Point3f{0, 0, 0}});
  std::string msg = open_error(root);
  CHECK(contains(msg, root.string()));
  CHECK(contains(msg, "poses.txt has 3 poses but clouds/ has 4 clouds"));

  // No clouds.
  for (int i = 0; i < 4; ++i) fs::remove(root / "clouds" / ("00000" + std::to_string(i) + ".ply"));
  CHECK(contains(open_error(root), "no .ply, .pcd, .bin or .xyz clouds"));

  fs::remove(root / "poses.txt");
  msg = open_error(root);
  CHECK(contains(msg, "poses.txt"));
  CHECK(contains(msg, "missing"));
  CHECK_FALSE(io::is_sequence_dir(root.string()));
}

TEST_CASE("io.read_points dispatches on the extension") {
  ScratchDir dir("point_file");
  const std::vector<Point3f> pts = {{1, 2, 3}, {4, 5, 6}};
  io::write_ply(dir.file("a.ply"), pts);
  for (const char* name : {"a.xyz", "a.dat", "a.txt", "A.XYZ"}) {
    write_bytes(dir.file(name), "1 2 3\n4 5 6\n");
  }
  for (const char* name : {"a.ply", "a.xyz", "a.dat", "a.txt", "A.XYZ"}) {
    CAPTURE(name);
    const io::Cloud c = io::read_points(dir.file(name));
    REQUIRE(c.points.size() == 2);
    CHECK(c.points[1].y == 5.0f);
  }
  const std::string bz = dir.file("scan.dat.bz2");
  write_bytes(bz, "BZh9");
  std::string msg = error_of([&] { io::read_points(bz); });
  CHECK(contains(msg, bz));
  CHECK(contains(msg, "compressed input: decompress first, e.g. bzip2 -dk FILE"));
  msg = error_of([&] { io::read_points(dir.file("cloud.las")); });
  CHECK(contains(msg, "unknown point-file extension '.las'"));
  CHECK(contains(error_of([&] { io::read_points(dir.file("noext")); }),
                 "unknown point-file extension"));
}

TEST_CASE("io.voxel_list is sorted and round-trips") {
  ScratchDir dir("voxels");
  const std::string p = dir.file("map.txt");
  std::vector<io::VoxelRecord> v = {
      {0.5, -1.25, 2.0, 0.85f}, {-0.5, 3.0, 1.0, -2.0f},       {0.5, -1.25, -2.0, 1.5f},
      {0.5, -2.0, 9.0, 0.4f},   {0.0078125, 1e-7, -0.0, 3.5f},
  };
  io::write_voxel_list(p, v);
  CHECK_FALSE(fs::exists(p + ".tmp"));
  CHECK(read_text(p) ==
        "-0.500000 3.000000 1.000000 -2.000000\n"
        "0.007812 0.000000 -0.000000 3.500000\n"
        "0.500000 -2.000000 9.000000 0.400000\n"
        "0.500000 -1.250000 -2.000000 1.500000\n"
        "0.500000 -1.250000 2.000000 0.850000\n");
  const std::vector<io::VoxelRecord> back = io::read_voxel_list(p);
  REQUIRE(back.size() == 5);
  CHECK(back[0].x == -0.5);
  CHECK(back[2].y == -2.0);
  CHECK(back[4].z == 2.0);
  CHECK(back[4].logodds == doctest::Approx(0.85f).epsilon(1e-6));

  // Random voxel centres survive within the 1e-6 print precision.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> cell(-500, 500);
  std::vector<io::VoxelRecord> many;
  for (int i = 0; i < 2000; ++i) {
    many.push_back({(cell(rng) + 0.5) * 0.05, (cell(rng) + 0.5) * 0.05, (cell(rng) + 0.5) * 0.05,
                    static_cast<float>(cell(rng)) / 100.0f});
  }
  io::write_voxel_list(p, many);
  const std::vector<io::VoxelRecord> many_back = io::read_voxel_list(p);
  REQUIRE(many_back.size() == many.size());
  for (std::size_t i = 1; i < many_back.size(); ++i) {
    const auto& a = many_back[i - 1];
    const auto& b = many_back[i];
    CHECK((a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z <= b.z)))));
  }
  std::sort(many.begin(), many.end(), [](const io::VoxelRecord& a, const io::VoxelRecord& b) {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  });
  std::string expected;
  for (std::size_t i = 0; i < many.size(); ++i) {
    CHECK(std::abs(many_back[i].x - many[i].x) <= 1e-6);
    CHECK(std::abs(many_back[i].logodds - many[i].logodds) <= 1e-6f);
    char line[512];
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", many[i].x, many[i].y, many[i].z,
                  static_cast<double>(many[i].logodds));
    expected += line;
  }
  CHECK(read_text(p) == expected);  // byte-identical to printf("%.6f")

  // Values that stress the fast formatter: exact ties, -0, rounding carries, large magnitudes.
  const std::vector<double> tricky = {0.0,    -0.0,      2.5e-6,          -2.5e-6,
                                      1.5e-6, 0.0000005, 999999.9999995,  1234567.891,
                                      -1e300, 0.1,       -0.049999999999, 1.0 / 3.0};
  std::vector<io::VoxelRecord> tv;
  for (std::size_t i = 0; i < tricky.size(); ++i) tv.push_back({double(i), 0.0, tricky[i], 0.0f});
  io::write_voxel_list(p, tv);
  std::string tricky_expected;
  for (std::size_t i = 0; i < tricky.size(); ++i) {
    char line[512];
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", double(i), 0.0, tricky[i], 0.0);
    tricky_expected += line;
  }
  CHECK(read_text(p) == tricky_expected);

  CHECK(contains(error_of([&] {
                   io::write_voxel_list(dir.file("nan.txt"), {{std::nan(""), 0.0, 0.0, 1.0f}});
                 }),
                 "non-finite coordinate"));
  CHECK_FALSE(fs::exists(dir.file("nan.txt")));
  const std::string bad = dir.file("bad.txt");
  write_bytes(bad, "1 2 3 4\n1 2 3\n");
  const std::string msg = error_of([&] { io::read_voxel_list(bad); });
  CHECK(contains(msg, bad));
  CHECK(contains(msg, "line 2: expected 4 numbers"));
}

namespace {
// The vertex count a PLY header declares, read independently of io::read_ply.
std::uint64_t header_vertex_count(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::string line;
  while (std::getline(f, line) && line.rfind("end_header", 0) != 0) {
    if (line.rfind("element vertex ", 0) == 0) return std::stoull(line.substr(15));
  }
  return 0;
}
}  // namespace

TEST_CASE("io.real data: TUM fr2/pioneer_slam2 sequence") {
  const std::string dir = knnocc::test::data_path("tum_fr2_pioneer_slam2");
  if (dir.empty()) {
    MESSAGE("../shared/data/tum_fr2_pioneer_slam2 not found; skipping");
    return;
  }
  CHECK(io::is_sequence_dir(dir));
  const io::Sequence seq = io::Sequence::open(dir);
  REQUIRE(seq.size() == 10);
  const io::Cloud c = seq.load_cloud(0);
  const std::uint64_t declared = header_vertex_count(seq.cloud_path(0));
  CHECK(declared > 50000);
  CHECK(declared < 80000);
  CHECK(c.points.size() == declared);
  CHECK(c.ids.empty());
  std::size_t bad = 0;
  for (const Point3f& q : c.points) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !(q.z > 0.0f && q.z < 10.0f)) ++bad;
  }
  CHECK(bad == 0);
  // Ground-truth quaternions have 4 decimals: accepted and normalised.
  CHECK(seq.pose(0).q.norm() == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(seq.pose(9).stamp > seq.pose(0).stamp);
}

TEST_CASE("io.real data: ORB-SLAM2 keyframes carry ids") {
  const std::string dir = knnocc::test::data_path("orbslam2_stereo_keyframes");
  if (dir.empty()) {
    MESSAGE("../shared/data/orbslam2_stereo_keyframes not found; skipping");
    return;
  }
  const io::Sequence seq = io::Sequence::open(dir);
  CHECK(seq.size() == 249);
  const io::Cloud c = seq.load_cloud(0);
  CHECK(c.points.size() == 182);
  REQUIRE(c.ids.size() == 182);
  std::vector<std::uint64_t> sorted = c.ids;
  std::sort(sorted.begin(), sorted.end());
  CHECK(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());
  std::size_t bad = 0;
  for (const Point3f& q : c.points) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) ++bad;
  }
  CHECK(bad == 0);
}

TEST_CASE("io.real data: OctoMap FR-079 scan.dat") {
  const std::string path = knnocc::test::scan_dat_path();  // decompressed by the ctest fixture
  if (path.empty()) {
    MESSAGE("scan.dat not decompressed into the build tree; skipping");
    return;
  }
  const io::Cloud c = io::read_points(path);
  CHECK(c.points.size() == 88206);
  double min_range = 1e9;
  double max_range = 0.0;
  for (const Point3f& q : c.points) {
    const double r = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z);
    min_range = std::min(min_range, r);
    max_range = std::max(max_range, r);
  }
  CHECK(min_range > 0.4);  // README: ranges 0.47-29.0 m
  CHECK(max_range < 29.5);
}
