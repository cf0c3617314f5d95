// knnocc demo --scene room: a simulated 16-beam LiDAR scans a furnished room from eight poses;
// the scans are inserted with the OctoMap model, checked against the room's true geometry, and a
// top view of the map is printed. Needs no data files.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/voxel_list.hpp>

#include "args.hpp"
#include "commands.hpp"
#include "output_set.hpp"

namespace knnocc::cli {

namespace room_demo {

struct Box {
  std::array<double, 3> lo, hi;
};

// A 10 m x 8 m x 3 m room: floor, ceiling, four walls, a partition with a door, furniture.
inline std::vector<Box> room() {
  return {
      {{-0.2, -0.2, -0.2}, {10.2, 8.2, 0.0}},  // floor
      {{-0.2, -0.2, 3.0}, {10.2, 8.2, 3.2}},   // ceiling
      {{-0.2, -0.2, 0.0}, {0.0, 8.2, 3.0}},    // walls
      {{10.0, -0.2, 0.0}, {10.2, 8.2, 3.0}},
      {{-0.2, -0.2, 0.0}, {10.2, 0.0, 3.0}},
      {{-0.2, 8.0, 0.0}, {10.2, 8.2, 3.0}},
      {{6.0, 0.0, 0.0}, {6.2, 3.0, 3.0}},  // partition, door between y = 3 and 4.2
      {{6.0, 4.2, 0.0}, {6.2, 8.0, 3.0}},
      {{6.0, 3.0, 2.1}, {6.2, 4.2, 3.0}},   // lintel above the door
      {{2.0, 2.0, 0.0}, {3.6, 3.0, 0.75}},  // table
      {{4.5, 5.5, 0.0}, {4.9, 5.9, 3.0}},   // pillar
      {{0.0, 6.6, 0.0}, {1.8, 8.0, 2.0}},   // cabinet
      {{8.0, 1.0, 0.0}, {9.2, 2.0, 1.2}},   // crate in the second room
  };
}

// Nearest t > 0 where origin + t * dir enters any box (slab test), or +inf.
inline double first_hit(const std::vector<Box>& boxes, const std::array<double, 3>& o,
                        const std::array<double, 3>& d) {
  double best = INFINITY;
  for (const Box& b : boxes) {
    double t0 = 1e-9, t1 = best;
    for (int a = 0; a < 3 && t0 <= t1; ++a) {
      if (d[a] == 0.0) {
        if (o[a] < b.lo[a] || o[a] > b.hi[a]) t0 = INFINITY;
        continue;
      }
      double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 <= t1) best = t0;
  }
  return best;
}

// Does the voxel centred at c (edge r) overlap a box?
inline bool touches_solid(const std::vector<Box>& boxes, const std::array<double, 3>& c, double r) {
  for (const Box& b : boxes) {
    bool overlap = true;
    for (int a = 0; a < 3; ++a)
      overlap = overlap && c[a] + r / 2 > b.lo[a] - 1e-9 && c[a] - r / 2 < b.hi[a] + 1e-9;
    if (overlap) return true;
  }
  return false;
}

// Is the voxel centred at c strictly inside a box (at least half a voxel from its faces)?
inline bool inside_solid(const std::vector<Box>& boxes, const std::array<double, 3>& c, double r) {
  for (const Box& b : boxes) {
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && c[a] - r / 2 > b.lo[a] && c[a] + r / 2 < b.hi[a];
    if (inside) return true;
  }
  return false;
}

}  // namespace room_demo

namespace {

CommandSpec make_room_demo_spec() {
  CommandSpec s;
  s.name = "demo --scene room";
  s.summary = "a simulated LiDAR scans a furnished room; OctoMap model, checked against the room";
  s.usage = "knnocc demo --scene room [--res R] [--seed S] [--out-voxels FILE]";
  s.text =
      "A simulated 16-beam LiDAR (1 degree azimuth, 1 cm range noise, 12 m range) scans a\n"
      "furnished 10 m x 8 m room from 8 poses; the scans go through the OctoMap model at --res.\n"
      "Prints the summary line of `knnocc map`, a check against the room's true geometry, and a\n"
      "top view of the map at sensor height.\n";
  s.groups.push_back(
      {"options",
       {Option::text("--scene", "NAME", "room for this demo").one_of({"tree", "room", "loop"}),
        Option::number("--res", "R", "voxel edge in metres")
            .fallback("0.1")
            .at_least(0.02)
            .at_most(1),
        Option::integer("--seed", "S", "random seed of the range noise").fallback("1").at_least(0),
        Option::text("--out-voxels", "FILE", "the map as a voxel list (x y z logodds per voxel)")},
       ""});
  return s;
}

}  // namespace

const CommandSpec& room_demo_spec() {
  static const CommandSpec spec = make_room_demo_spec();
  return spec;
}

namespace {

// One 16-beam scan (1 degree azimuth, 12 m range, 1 cm range noise) from o.
std::vector<Point3f> lidar_scan(const std::vector<room_demo::Box>& boxes,
                                const std::array<double, 3>& o, std::mt19937_64& rng,
                                std::normal_distribution<double>& noise) {
  constexpr double kPi = 3.14159265358979323846;
  constexpr double kRange = 12.0;
  std::vector<Point3f> scan;
  for (int beam = 0; beam < 16; ++beam) {
    const double el = (-15.0 + 2.0 * beam) * kPi / 180.0;
    for (int az = 0; az < 360; ++az) {
      const double a = az * kPi / 180.0;
      const std::array<double, 3> d = {std::cos(el) * std::cos(a), std::cos(el) * std::sin(a),
                                       std::sin(el)};
      const double t = room_demo::first_hit(boxes, o, d);
      if (!(t < kRange)) continue;  // no return
      const double r = t + noise(rng);
      scan.push_back(
          Point3f{float(o[0] + r * d[0]), float(o[1] + r * d[1]), float(o[2] + r * d[2])});
    }
  }
  return scan;
}

// The map against the true geometry.
void print_check(const OccupancyMap<OcKey>& map, const std::vector<room_demo::Box>& boxes,
                 double res) {
  std::size_t on_surface = 0, free_inside = 0;
  const auto& g = map.grid();
  map.for_each_voxel([&](const OcKey& k, float v) {
    const std::array<double, 3> c = {g.index_to_coord(k[0]), g.index_to_coord(k[1]),
                                     g.index_to_coord(k[2])};
    if (map.is_occupied(v))
      on_surface += room_demo::touches_solid(boxes, c, res);
    else
      free_inside += room_demo::inside_solid(boxes, c, res);
  });
  const std::size_t occupied = map.count_voxels().occupied;
  std::printf(
      "check: %zu of %zu occupied voxels touch a real surface (%.1f %%); "
      "%zu free voxels lie inside solid objects\n",
      on_surface, occupied, occupied ? 100.0 * on_surface / occupied : 0.0, free_inside);
}

// Top view at sensor height from coarse-depth queries (2x2x2 voxels per character).
void print_top_view(const OccupancyMap<OcKey>& map) {
  std::printf(
      "top view at z = 1.2 m, 2 voxels per character ('#' occupied, '.' free, ' ' unknown):\n");
  const auto& g = map.grid();
  const int depth = OcKey::depth - 1;
  const double cell = g.node_size(depth);
  for (double y = 8.3 - cell / 2; y > -0.3; y -= cell) {
    std::string row;
    for (double x = -0.3 + cell / 2; x < 10.3; x += cell) {
      OcKey k;
      char ch = ' ';
      if (g.coord_to_key(x, y, 1.2, k))
        if (const auto v = map.logodds_at_depth(k, depth)) ch = map.is_occupied(*v) ? '#' : '.';
      row += ch;
    }
    std::printf("  %s\n", row.c_str());
  }
}

}  // namespace

int run_room_demo(const Args& args) {
  check_outputs(requested_outputs(args, {"--out-voxels"}));
  const double res = args.number("--res");
  const long seed = args.integer("--seed");
  const auto boxes = room_demo::room();
  const std::array<std::array<double, 3>, 8> poses = {{{1.0, 1.0, 1.2},
                                                       {3.0, 4.5, 1.2},
                                                       {1.2, 5.5, 1.2},
                                                       {4.0, 7.0, 1.2},
                                                       {5.0, 3.6, 1.2},
                                                       {7.5, 3.6, 1.2},
                                                       {8.5, 6.5, 1.2},
                                                       {7.0, 1.0, 1.2}}};
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
  std::normal_distribution<double> noise(0.0, 0.01);
  std::printf(
      "knnocc demo: simulated 16-beam LiDAR in a 10 m x 8 m room, %zu scans, "
      "OctoMap model at %g m (seed %ld)\n",
      poses.size(), res, seed);
  const auto t0 = std::chrono::steady_clock::now();
  OccupancyMap<OcKey> map(res);
  ScanInserter<OcKey> inserter(map);
  std::size_t points = 0;
  for (const auto& o : poses)
    points += inserter
                  .insert_point_cloud(Point3f{float(o[0]), float(o[1]), float(o[2])},
                                      lidar_scan(boxes, o, rng, noise))
                  .points;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto counts = map.count_voxels();
  std::printf("clouds %zu points %zu occupied %zu free %zu seconds %.3f\n", poses.size(), points,
              counts.occupied, counts.free, seconds);
  print_check(map, boxes, res);
  print_top_view(map);
  if (args.has("--out-voxels")) {
    io::write_voxel_list(args.str("--out-voxels"), io::voxel_records(map));
    std::printf("wrote %s\n", args.str("--out-voxels").c_str());
  }
  return 0;
}

}  // namespace knnocc::cli
