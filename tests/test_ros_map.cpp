// ROS map_server maps (io/ros_map.hpp): the YAML and PGM written, parsed back by hand and by
// read_ros_map, a map_saver-style file read, malformed files refused, file names that YAML would
// misread written quoted (the tool's cli.resources.grid_yaml_names reads them with PyYAML).
#include <doctest/doctest.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include <knnocc/io/detail/yaml_scalar.hpp>
#include <knnocc/io/ros_map.hpp>

#include "io_files.hpp"
#include "test_support.hpp"

namespace io = knnocc::io;
using knnocc::OccupancyGrid2D;
using namespace knnocc::test::io_files;

namespace {

OccupancyGrid2D sample_grid() {
  OccupancyGrid2D g;
  g.resolution = 0.05;
  g.origin[0] = -1.25;
  g.origin[1] = 3.5;
  g.width = 4;
  g.height = 3;
  // Row y = 0 (the bottom): occupied, free, unknown, free; y = 1 all unknown; y = 2 (the top):
  // free, free, occupied, occupied.
  g.cells = {100, 0, -1, 0, -1, -1, -1, -1, 0, 0, 100, 100};
  return g;
}

}  // namespace

TEST_CASE("ros_map.written files parse back: YAML keys, P5 pixels top row first") {
  ScratchDir dir("ros_map");
  const std::string yaml = dir.file("floor.yaml");
  const OccupancyGrid2D g = sample_grid();
  io::write_ros_map(yaml, g);
  CHECK(read_text(yaml) ==
        "image: \"floor.pgm\"\nmode: trinary\nresolution: 0.05\norigin: [-1.25, 3.5, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const std::string pgm = read_text(dir.file("floor.pgm"));
  const std::string header = "P5\n# knnocc occupancy grid, 0.050000 m/pixel\n4 3\n255\n";
  REQUIRE(pgm.size() == header.size() + 12);
  CHECK(pgm.substr(0, header.size()) == header);
  const std::string pixels = pgm.substr(header.size());
  const std::string expect = {'\xfe', '\xfe', '\x00', '\x00',   // top row: y = 2
                              '\xcd', '\xcd', '\xcd', '\xcd',   // y = 1: unknown (205)
                              '\x00', '\xfe', '\xcd', '\xfe'};  // bottom row: y = 0
  CHECK(pixels == expect);
  const OccupancyGrid2D back = io::read_ros_map(yaml);
  CHECK(back.width == g.width);
  CHECK(back.height == g.height);
  CHECK(back.resolution == g.resolution);
  CHECK(back.origin[0] == g.origin[0]);
  CHECK(back.origin[1] == g.origin[1]);
  CHECK(back.cells == g.cells);
  CHECK_FALSE(knnocc::test::has_temporary_beside(yaml));
}

TEST_CASE("ros_map.a map_saver file with comments and another image name is read") {
  ScratchDir dir("ros_map_saver");
  write_bytes(dir.file("map.yaml"),
              "image: saved.pgm\nresolution: 0.100000\norigin: [-2.000000, -1.000000, 0.000000]\n"
              "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n\n");
  write_bytes(
      dir.file("saved.pgm"),
      std::string("P5\n# CREATOR: map_saver.cpp 0.100 m/pix\n2 1\n255\n") + '\x00' + '\xfe');
  const OccupancyGrid2D g = io::read_ros_map(dir.file("map.yaml"));
  REQUIRE(g.width == 2);
  CHECK(g.origin[0] == -2.0);
  CHECK(g.cells == std::vector<std::int8_t>{100, 0});
}

TEST_CASE("ros_map.malformed maps and an empty grid are errors naming the file") {
  ScratchDir dir("ros_map_bad");
  const std::string yaml = dir.file("m.yaml");
  CHECK(contains(error_of([&] { io::write_ros_map(yaml, OccupancyGrid2D{}); }), "empty"));
  CHECK_FALSE(std::filesystem::exists(yaml));
  write_bytes(yaml, "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n");
  CHECK(contains(error_of([&] { io::read_ros_map(yaml); }), "needs image"));
  write_bytes(yaml,
              "image: m.pgm\nresolution: -1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n"
              "free_thresh: 0.196\n");
  CHECK(contains(error_of([&] { io::read_ros_map(yaml); }), "invalid resolution"));
  write_bytes(yaml,
              "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 0.65\n"
              "free_thresh: 0.196\n");
  const std::string pgm = dir.file("m.pgm");
  write_bytes(pgm, "P5\n3 3\n255\n\x01\x02");
  std::string msg = error_of([&] { io::read_ros_map(yaml); });
  CHECK(contains(msg, pgm));
  CHECK(contains(msg, "truncated"));
  write_bytes(pgm, "P2\n1 1\n255\n0\n");
  CHECK(contains(error_of([&] { io::read_ros_map(yaml); }), "P5"));
}

TEST_CASE("ros_map.image names YAML would misread are written quoted and read back") {
  ScratchDir dir("ros_map_names");
  const std::string names[] = {
      "lab #2",     "map: v2",        "[old] lab", "#h",     "- map",  "new\nline",
      "'q'",        "\"dq\"",         "a{b}&*!%@", "b\\c",   "t\tab",  "caf\xc3\xa9",
      "c1\xc2\x85", "ls\xe2\x80\xa8", " lead",     "trail ", "\x1b[1m"};
  for (const std::string& n : names) {
    CAPTURE(n);
    const std::string yaml = dir.file(n + ".yaml");
    io::write_ros_map(yaml, sample_grid());
    const std::string text = read_text(yaml);
    CHECK(text.find('\n') == text.find("\nmode: trinary"));      // the image entry is one line
    CHECK(io::read_ros_map(yaml).cells == sample_grid().cells);  // found the image it names
  }
  // Not UTF-8: refused before anything is written.
  const std::string bad = dir.file("bad\xff.yaml");
  CHECK(contains(error_of([&] { io::write_ros_map(bad, sample_grid()); }), "not valid UTF-8"));
  CHECK_FALSE(std::filesystem::exists(dir.file("bad\xff.pgm")));
}

TEST_CASE("ros_map.YAML scalars: the escapes, quotes and comments of one line") {
  namespace d = knnocc::io::detail;
  const auto read = [](const std::string& text) {
    std::string out;
    return d::yaml_scalar(text.data(), text.data() + text.size(), out) ? out : "<error>";
  };
  std::string q;
  REQUIRE(d::yaml_double_quoted("a\"b\\c\n\x01\x7f", q));
  CHECK(q == "\"a\\\"b\\\\c\\n\\x01\\x7F\"");
  CHECK(read(q) == "a\"b\\c\n\x01\x7f");
  CHECK(read("plain.pgm  # a comment") == "plain.pgm");
  CHECK(read("lab#2.pgm") == "lab#2.pgm");  // '#' inside a plain scalar is text
  CHECK(read("'it''s.pgm' # c") == "it's.pgm");
  CHECK(read("\"\\u00e9\\x41\\N\"") ==
        "\xc3\xa9"
        "A\xc2\x85");
  CHECK(read("\"open") == "<error>");
  CHECK(read("\"a\" b") == "<error>");
  CHECK(read("\"\\q\"") == "<error>");
  CHECK(read("\"\\uD800\"") == "<error>");
}
