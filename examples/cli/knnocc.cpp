// knnocc: the command-line tool (the contract is in README.md, "Command-line tool").
// Every failure is one line on stderr and exit status 2; outputs are written to a temporary
// file and renamed, so a failed run leaves nothing half-written.

#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
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
#include "output_set.hpp"
#include "resource_limits.hpp"
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
  knnocc::io::remove_temporaries_on_signal();
  // Allocations past the memory limit fail (std::bad_alloc, one line below) instead of the
  // kernel killing the process; `map --memory-limit` sets its own.
  knnocc::cli::apply_memory_limit(knnocc::cli::default_memory_limit());
  try {
    int rc = 2;
    if (command == "map") {
      rc = knnocc::cli::run_map(args);
    } else if (command == "demo") {
      rc = knnocc::cli::run_demo(args);
    } else if (command == "track") {
      rc = knnocc::cli::run_track(args);
    } else if (command == "sim") {
      rc = knnocc::cli::run_sim(args);
    } else if (command == "eval") {
      rc = knnocc::cli::run_eval(args);
    } else if (command == "info") {
      rc = knnocc::cli::run_info(args);
    } else if (command == "convert") {
      rc = knnocc::cli::run_convert(args);
    } else if (command == "view") {
      rc = knnocc::cli::run_view(args);
    } else if (command == "version" || command == "--version") {
      std::printf("knnocc %s\n", KNNOCC_VERSION_STRING);
      rc = 0;
    } else {
      std::fprintf(stderr, "knnocc: unknown command '%s' (see knnocc --help)\n",
                   knnocc::io::printable(command).c_str());
      return 2;
    }
    knnocc::cli::check_stdout();  // output lost on a full disk or /dev/full fails the command
    return rc;
  } catch (const knnocc::cli::UsageError& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(),
                 knnocc::io::printable(e.what()).c_str());
  } catch (const knnocc::io::Error& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(), e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "knnocc %s: out of memory: the command needs more than the memory limit of %s "
                 "(map --memory-limit; default 80 %% of this machine's memory)\n",
                 command.c_str(),
                 knnocc::cli::format_bytes(knnocc::cli::memory_limit_bytes()).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", command.c_str(),
                 knnocc::io::printable(e.what()).c_str());
  }
  return 2;
}
