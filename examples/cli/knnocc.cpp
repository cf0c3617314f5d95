// knnocc: the command-line tool (the contract is in README.md, "Command-line tool").
// Every failure is one line on stderr and exit status 2; outputs are written to a temporary
// file and renamed, so a failed run leaves nothing half-written.

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <knnocc/io/error.hpp>
#include <knnocc/version.hpp>

#include "args.hpp"
#include "convert_command.hpp"
#include "demo_command.hpp"
#include "eval_command.hpp"
#include "info_command.hpp"
#include "map_command.hpp"
#include "sim_command.hpp"
#include "track_command.hpp"
#include "view_command.hpp"

namespace {

const char* kUsage = R"(usage: knnocc <command> [options]     (knnocc <command> --help for details)

commands:
  demo     the embedded default job: the paper's experiment on a simulated tree scene, OctoMap
           model against k-NN model (Table 1); `demo --scene room`: a LiDAR room demo
  map      build an occupancy map from a sequence folder, a .graph file or a point file
           (--model octomap|knn)
  track    follow s_p and its normal distribution over a keyframe sequence (k-NN tracker)
  sim      write the simulated tree scene as a sequence folder plus its reference shapes
  eval     compare a map with reference shapes (the paper's Table 1 metrics)
  info     what a map (.bt/.ot), cloud, scan graph or sequence folder holds
  convert  maps and clouds between formats (.bt .ot .ply .pcd .xyz .bin .png, voxel lists)
  view     maps in 3D: one self-contained web page (three.js embedded)
  version  print the version
)";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "map") return knnocc::cli::run_map(args);
    if (command == "demo") return knnocc::cli::run_demo(args);
    if (command == "track") return knnocc::cli::run_track(args);
    if (command == "sim") return knnocc::cli::run_sim(args);
    if (command == "eval") return knnocc::cli::run_eval(args);
    if (command == "info") return knnocc::cli::run_info(args);
    if (command == "convert") return knnocc::cli::run_convert(args);
    if (command == "view") return knnocc::cli::run_view(args);
    if (command == "version" || command == "--version") {
      std::printf("knnocc %s\n", KNNOCC_VERSION_STRING);
      return 0;
    }
    std::fprintf(stderr, "knnocc: unknown command '%s' (see knnocc --help)\n", command.c_str());
    return 2;
  } catch (const knnocc::cli::UsageError& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(), e.what());
  } catch (const knnocc::io::Error& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(), e.what());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(), e.what());
  }
  return 2;
}
