#pragma once
// The knnocc tool's commands: one table drives dispatch, `knnocc --help` and docs/cli.md. Each
// command lives in its own <name>_command.cpp (compiled into the knnocc_cli library) and exposes
// its CommandSpec (the options it takes, declared once, args.hpp) and its run function.

#include <string>
#include <vector>

#include "args.hpp"

namespace knnocc::cli {

/// One variant of a command: `demo` runs the tree scene, `demo --scene room` the room demo.
struct Command {
  const CommandSpec& (*spec)();
  int (*run)(const Args&);
  /// The word after the command that selects this variant (e.g. "room" for `demo --scene room`),
  /// empty for the command's main form.
  const char* variant = "";
};

/// Every command, in the order `knnocc --help` lists them; variants follow their command.
const std::vector<Command>& commands();

/// The command `argv[0]` names, choosing a variant by `--scene` (demo); nullptr if unknown.
const Command* find_command(const std::string& name, const std::vector<std::string>& args);

/// `knnocc --help`: the commands and what each does.
std::string top_level_help();

/// docs/cli.md: every command's usage, text and options (`knnocc help --markdown`).
std::string cli_markdown();

// The commands (each in its <name>_command.cpp).
const CommandSpec& map_spec();
int run_map(const Args& args);
const CommandSpec& merge_spec();
int run_merge(const Args& args);
const CommandSpec& tile_spec();
int run_tile(const Args& args);
const CommandSpec& demo_spec();
int run_demo(const Args& args);
const CommandSpec& room_demo_spec();
int run_room_demo(const Args& args);
const CommandSpec& loop_demo_spec();
int run_loop_demo(const Args& args);
const CommandSpec& track_spec();
int run_track(const Args& args);
const CommandSpec& sim_spec();
int run_sim(const Args& args);
const CommandSpec& eval_spec();
int run_eval(const Args& args);
const CommandSpec& info_spec();
int run_info(const Args& args);
const CommandSpec& convert_spec();
int run_convert(const Args& args);
const CommandSpec& view_spec();
int run_view(const Args& args);
const CommandSpec& help_spec();
int run_help(const Args& args);
const CommandSpec& version_spec();
int run_version(const Args& args);

}  // namespace knnocc::cli
