// The C++ half of bench/bench_python.py: the library's own time for the calls the Python bench
// makes through the module, measured in the same run. One round (one process):
//   insert  the TUM clouds (world frame, float, as the tool gives them) into a new OccupancyMap
//           through one ScanInserter on one thread: what OccupancyMap.insert_point_cloud does
//           (after one untimed map, as the Python side has made maps before its timed ones);
//   query   the occupancy of the points in QUERIES (raw float64 x y z triples), one point at a
//           time as a C++ caller writes it: what occupancy_at does.
// Prints "insert_seconds S query_seconds S insert_cpu S query_cpu S" (wall-clock and CPU time:
// on a shared machine the wall clock also counts the time other processes take) and writes OUT.ot
// (the map) and OUT.occ (one int8 per query: -1 unknown, 0 free, 1 occupied) for the Python side to
// compare with its own.
//
//   bench_python_ref TUM_DIR RES QUERIES OUT

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include <knnocc/insertion/scan_inserter.hpp>
#include <knnocc/io/octomap_tree.hpp>

#include "bench_common.hpp"

int main(int argc, char** argv) {
  using namespace knnocc;
  if (argc != 5) {
    std::fprintf(stderr, "usage: bench_python_ref TUM_DIR RES QUERIES OUT\n");
    return 2;
  }
  const double res = std::atof(argv[2]);
  const auto scans = bench::sequence_scans(argv[1]);
  std::ifstream in(argv[3], std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<Point3d> queries(bytes.size() / sizeof(Point3d));
  bytes.copy(reinterpret_cast<char*>(queries.data()), queries.size() * sizeof(Point3d));

  auto insert = [&](OccupancyMap<>& map) {
    ScanInserter<> inserter(map);
    for (const auto& scan : scans) inserter.insert_point_cloud(scan.origin, scan.points);
  };
  {  // a warm-up map, as the Python process has built maps before its timed ones
    OccupancyMap<> warm(res);
    insert(warm);
  }
  const auto cpu = [] { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; };
  double t = bench::now(), c = cpu();
  OccupancyMap<> map(res);
  insert(map);
  const double insert_seconds = bench::now() - t, insert_cpu = cpu() - c;

  std::vector<std::int8_t> occupancy(queries.size());
  t = bench::now();
  c = cpu();
  for (std::size_t i = 0; i < queries.size(); ++i) {
    OcKey key;
    std::optional<bool> occupied;
    if (map.grid().coord_to_key(queries[i].x, queries[i].y, queries[i].z, key))
      occupied = map.is_occupied(key);
    occupancy[i] = occupied ? static_cast<std::int8_t>(*occupied) : std::int8_t{-1};
  }
  const double query_seconds = bench::now() - t, query_cpu = cpu() - c;

  const std::string out = argv[4];
  io::write_ot(out + ".ot", map);
  std::ofstream(out + ".occ", std::ios::binary)
      .write(reinterpret_cast<const char*>(occupancy.data()),
             static_cast<std::streamsize>(occupancy.size()));
  std::printf("insert_seconds %.6f query_seconds %.6f insert_cpu %.6f query_cpu %.6f\n",
              insert_seconds, query_seconds, insert_cpu, query_cpu);
  return 0;
}
