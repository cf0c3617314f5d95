// OctoMap ScanGraph files (io/scan_graph.hpp), against liboctomap where it is installed.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <knnocc/io/kitti.hpp>
#include <knnocc/io/pcd.hpp>
#include <knnocc/io/ply.hpp>
#include <knnocc/io/scan_graph.hpp>
#include <knnocc/io/scan_source.hpp>
#include <knnocc/io/sequence.hpp>
#include <knnocc/io/trajectory.hpp>

#include "../io_files.hpp"
#include "../test_support.hpp"
#include "counting_new.hpp"

#if KNNOCC_HAVE_OCTOMAP
#include <octomap/ScanGraph.h>
#endif

using namespace knnocc::test::io_files;  // io, fs, Point3f, file helpers

namespace {

void check_graph_error(const std::string& name, const std::string& bytes,
                       const std::string& needle) {
  CAPTURE(name);
  const fs::path path = sources_file(name);
  write_file(path, bytes);
  knnocc::test::reset_largest_allocation();
  try {
    (void)io::read_scan_graph(path.string());
    FAIL("no error");
  } catch (const io::Error& e) {
    const std::size_t largest = knnocc::test::largest_allocation();
    CHECK(largest < bytes.size() + 4096);
    CHECK(e.file() == path.string());
    CHECK_MESSAGE(e.problem().find(needle) != std::string::npos, e.problem());
  }
}

}  // namespace

TEST_CASE("scan_graph.round trip") {
  const io::ScanGraph g = sample_graph();
  const std::string path = sources_file("sample.graph").string();
  io::write_scan_graph(path, g);
  const io::ScanGraph back = io::read_scan_graph(path);
  REQUIRE(back.nodes.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(back.nodes[i].id == g.nodes[i].id);
    CHECK(back.nodes[i].pose.t == g.nodes[i].pose.t);
    CHECK(back.nodes[i].pose.q.coeffs() == g.nodes[i].pose.q.coeffs());
    REQUIRE(back.nodes[i].points.size() == g.nodes[i].points.size());
    for (std::size_t k = 0; k < g.nodes[i].points.size(); ++k) {
      const Point3f &a = back.nodes[i].points[k], &b = g.nodes[i].points[k];
      CHECK(((a.x == b.x && a.y == b.y && a.z == b.z) || (std::isnan(a.y) && std::isnan(b.y))));
    }
  }
  REQUIRE(back.edges.size() == 1);
  CHECK(back.edges[0].second == 11);
  CHECK(back.edges[0].weight == 0.25);
  // Written again: the same bytes.
  const std::string again = sources_file("again.graph").string();
  io::write_scan_graph(again, back);
  CHECK(read_file(again) == read_file(path));
}

TEST_CASE("scan_graph.malformed files") {
  const std::string path = sources_file("good.graph").string();
  io::write_scan_graph(path, sample_graph());
  const std::string good = read_file(path);
  check_graph_error("empty.graph", "", "truncated while reading node count");
  check_graph_error("truncated.graph", good.substr(0, good.size() - 100), "truncated");
  check_graph_error("trailing.graph", good + "x", "unexpected bytes");
  std::string huge;
  append_le(huge, std::uint32_t{4000000000u});
  huge.append(200, '\0');
  check_graph_error("huge_nodes.graph", huge, "node count is 4000000000");
  std::string points;
  append_le(points, std::uint32_t{1});
  append_le(points, std::uint32_t{3000000000u});
  points.append(100, '\0');
  check_graph_error("huge_points.graph", points, "point count is 3000000000");
  std::string marker = good;
  marker[8] = 4;  // first point's "3"
  check_graph_error("marker.graph", marker, "size marker 4 instead of 3");
  // Node 0's pose: after 4 + 4 + 100 * 28 bytes; translation marker, 3 doubles, rotation marker.
  const std::size_t pose0 = 8 + 100 * 28;
  std::string nan_pose = good;
  const double nan = std::nan("");
  std::memcpy(&nan_pose[pose0 + 4], &nan, 8);
  check_graph_error("nan_pose.graph", nan_pose, "node 0: non-finite pose value");
  std::string bad_q = good;
  const double two = 2.0;
  std::memcpy(&bad_q[pose0 + 32], &two, 8);
  check_graph_error("bad_quaternion.graph", bad_q, "quaternion norm");
  io::ScanGraph dup = sample_graph();
  dup.nodes[2].id = dup.nodes[0].id;
  io::write_scan_graph(path, dup);
  check_graph_error("dup.graph", read_file(path), "two nodes have the id 1");
  io::ScanGraph dangling = sample_graph();
  dangling.edges[0].second = 99;
  io::write_scan_graph(path, dangling);
  check_graph_error("dangling.graph", read_file(path), "edge 0 refers to unknown node id 99");
}

#if KNNOCC_HAVE_OCTOMAP
TEST_CASE("scan_graph.liboctomap reads ours and we read liboctomap's") {
  // liboctomap -> us
  octomap::ScanGraph theirs;
  knnocc::test::Rng rng(8);
  std::uniform_real_distribution<float> u(-5.f, 5.f);
  std::vector<octomap::ScanNode*> nodes;
  for (int i = 0; i < 4; ++i) {
    auto* pc = new octomap::Pointcloud();
    for (int k = 0; k < 50 * (i + 1); ++k) pc->push_back(u(rng), u(rng), u(rng));
    nodes.push_back(theirs.addNode(pc, octomap::pose6d(i, -i, 0.5 * i, 0.1 * i, 0.2, -0.3 * i)));
  }
  theirs.addEdge(nodes[0], nodes[3], octomap::pose6d(1, 2, 3, 0, 0, 0.5));
  const std::string path = sources_file("octomap.graph").string();
  REQUIRE(theirs.writeBinary(path));
  const io::ScanGraph ours = io::read_scan_graph(path);
  REQUIRE(ours.nodes.size() == 4);
  for (std::size_t i = 0; i < 4; ++i) {
    const octomap::ScanNode& n = *nodes[i];
    CHECK(ours.nodes[i].id == n.id);
    REQUIRE(ours.nodes[i].points.size() == n.scan->size());
    std::size_t differing = 0;
    for (std::size_t k = 0; k < n.scan->size(); ++k) {
      const octomap::point3d& p = (*n.scan)[k];
      const Point3f& q = ours.nodes[i].points[k];
      differing += p.x() != q.x || p.y() != q.y || p.z() != q.z;
    }
    CHECK(differing == 0);
    CHECK(ours.nodes[i].pose.t.x() == n.pose.trans().x());
    CHECK(ours.nodes[i].pose.q.w() == n.pose.rot().u());
    CHECK(ours.nodes[i].pose.q.z() == n.pose.rot().z());
  }
  REQUIRE(ours.edges.size() == 1);
  CHECK(ours.edges[0].first == nodes[0]->id);
  CHECK(ours.edges[0].second == nodes[3]->id);

  // us -> liboctomap
  const std::string mine = sources_file("ours.graph").string();
  io::write_scan_graph(mine, sample_graph());
  octomap::ScanGraph read;
  REQUIRE(read.readBinary(mine));
  REQUIRE(read.size() == 3);
  const io::ScanGraph g = sample_graph();
  std::size_t i = 0;
  for (auto it = read.begin(); it != read.end(); ++it, ++i) {
    CHECK((*it)->id == g.nodes[i].id);
    CHECK((*it)->scan->size() == g.nodes[i].points.size());
    CHECK((*it)->pose.trans().y() == doctest::Approx(g.nodes[i].pose.t.y()));
    CHECK((*it)->pose.rot().u() == doctest::Approx(g.nodes[i].pose.q.w()));
    CHECK((*(*it)->scan)[7].x() == g.nodes[i].points[7].x);
  }
  CHECK(read.edges_end() - read.edges_begin() == 1);
}
#endif
