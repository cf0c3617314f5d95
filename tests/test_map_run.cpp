// What `knnocc map` does around the mapper (examples/cli/map_run.hpp): --crop keeps ids and
// colours with their points, a cloud that misses the key range is refused with its likely cause,
// and --points-frame world maps world-frame clouds to the same map as their sensor-frame
// originals (the map command run in-process, as the tool runs it).

#include <doctest/doctest.h>

#ifdef KNNOCC_TEST_TOOL_HEADERS

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>

#include "commands.hpp"
#include "map_run.hpp"
#include "test_support.hpp"

namespace cli = knnocc::cli;
namespace io = knnocc::io;
using knnocc::Point3f;
using knnocc::Rgb;

namespace {

int run_command(const std::string& name, const std::vector<std::string>& words) {
  const cli::Command* c = cli::find_command(name, words);
  REQUIRE(c != nullptr);
  return c->run(cli::Args(c->spec(), words));
}

std::string problem_of(const io::Cloud& cloud, double res) {
  try {
    cli::check_key_range(cloud, knnocc::Grid<knnocc::OcKey>(res), "cloud.txt");
  } catch (const io::Error& e) {
    CHECK(e.file() == "cloud.txt");
    return e.problem();
  }
  return "";
}

}  // namespace

TEST_CASE("map_run.crop_cloud keeps ids, colours and SLAM counters with their points") {
  io::Cloud c;
  c.points = {{1, 0, 0}, {5, 0, 0}, {0, 2, 0}, {0, 0, 9}};
  c.ids = {10, 11, 12, 13};
  c.colors = {{1, 1, 1}, {2, 2, 2}, {3, 3, 3}, {4, 4, 4}};
  c.evidence = {{1, 2, 3}, {4, 5, 6}, {7, 8, 9}, {10, 11, 12}};
  cli::crop_cloud(c, 3.0);
  REQUIRE(c.points.size() == 2);
  CHECK(c.points[1].y == 2.0f);
  CHECK(c.ids == std::vector<std::uint64_t>{10, 12});
  CHECK(c.colors == std::vector<Rgb>{{1, 1, 1}, {3, 3, 3}});
  REQUIRE(c.evidence.size() == 2);
  CHECK(c.evidence[1].found == 7);
  CHECK(c.evidence[1].observations == 9);
  cli::crop_cloud(c, -1.0);  // no crop
  CHECK(c.points.size() == 2);
}

TEST_CASE("map_run.a cloud that misses the key range names the likely cause") {
  io::Cloud cloud;
  // "stamp x y z" read as x y z: x is a Unix time.
  for (int i = 0; i < 100; ++i)
    cloud.points.push_back({1.69e9f + static_cast<float>(i), 1.0f, 2.0f});
  std::string why = problem_of(cloud, 0.1);
  CHECK(why.find("100 of 100 points lie outside the map's key range") != std::string::npos);
  CHECK(why.find("time stamp") != std::string::npos);
  // Millimetres: a room of 8000 mm at 0.1 m voxels (key range +-3276.8 m).
  cloud.points.clear();
  for (int i = 0; i < 100; ++i) cloud.points.push_back({4000.0f + i, 1200.0f, -300.0f});
  why = problem_of(cloud, 0.1);
  CHECK(why.find("millimetres") != std::string::npos);
  CHECK(problem_of(cloud, 0.5).empty());  // within +-16 km at 0.5 m
  // Most points inside: fine (the map skips the others and says how many).
  for (int i = 0; i < 1000; ++i) cloud.points.push_back({1.0f, 2.0f, 3.0f});
  CHECK(problem_of(cloud, 0.1).empty());
  // NaN points are not counted (the map skips and counts them too).
  cloud.points.assign(50, Point3f{std::nanf(""), 0.0f, 0.0f});
  CHECK(problem_of(cloud, 0.1).empty());
}

TEST_CASE("map_run.--points-frame world gives the map of the sensor-frame clouds") {
  const std::filesystem::path dir = std::filesystem::path(KNNOCC_BINARY_DIR) / "map_run_test";
  std::filesystem::remove_all(dir);
  // Poses and points whose products and sums are exact in float and double (half turns about z,
  // quarter-metre steps, points on a 1/64 m lattice): both runs then hold the same world points
  // bit for bit, and so must build the same map.
  knnocc::test::Rng rng(8);
  std::uniform_int_distribution<int> u(-192, 192);
  std::vector<io::Pose> poses(4);
  std::vector<io::Cloud> sensor(4), world(4);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    poses[i].t = Eigen::Vector3d(0.25 * i, 0.5, -0.75 * i);
    poses[i].q = i % 2 ? Eigen::Quaterniond(0, 0, 0, 1) : Eigen::Quaterniond::Identity();
    for (int j = 0; j < 400; ++j)
      sensor[i].points.push_back({u(rng) / 64.0f, u(rng) / 64.0f, u(rng) / 256.0f});
    io::transform_to_world(poses[i], sensor[i].points, world[i].points);
  }
  const auto write = [&](const std::string& name, const std::vector<io::Cloud>& clouds) {
    std::vector<const io::Cloud*> ptrs;
    for (const io::Cloud& c : clouds) ptrs.push_back(&c);
    io::write_sequence((dir / name).string(), poses, ptrs);
  };
  write("sensor", sensor);
  write("world", world);
  const std::string a = (dir / "sensor.voxels").string(), b = (dir / "world.voxels").string();
  CHECK(run_command("map", {"-i", (dir / "sensor").string(), "-r", "0.1", "-o", a}) == 0);
  CHECK(run_command("map", {"-i", (dir / "world").string(), "-r", "0.1", "--points-frame", "world",
                            "-o", b}) == 0);
  const std::string va = knnocc::test::read_file(a), vb = knnocc::test::read_file(b);
  CHECK(va.size() > 1000);
  CHECK(va == vb);
}

#endif
