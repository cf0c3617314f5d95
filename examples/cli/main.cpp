// knnocc: the command-line tool (docs/cli.md; the commands are in commands.cpp's table).
// Every failure is one line on stderr and exit status 2; outputs are written to a temporary
// file and renamed, so a failed run leaves nothing half-written.

#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <knnocc/io/error.hpp>

#include "commands.hpp"
#include "help_text.hpp"
#include "output_set.hpp"
#include "resource_limits.hpp"

namespace {

int run(const knnocc::cli::Command& command, const std::vector<std::string>& words) {
  const knnocc::cli::Args args(command.spec(), words);
  if (args.help()) {
    std::fputs(knnocc::cli::help_text(command.spec()).c_str(), stdout);
    return 0;
  }
  const int rc = command.run(args);
  knnocc::cli::check_stdout();  // output lost on a full disk or /dev/full fails the command
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  namespace cli = knnocc::cli;
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(cli::top_level_help().c_str(), argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  std::string name = argv[1];
  if (name == "--version") name = "version";
  const std::vector<std::string> words(argv + 2, argv + argc);
  const cli::Command* command = cli::find_command(name, words);
  if (!command) {
    std::fprintf(stderr, "knnocc: unknown command '%s' (see knnocc --help)\n",
                 knnocc::io::printable(name).c_str());
    return 2;
  }
  knnocc::io::remove_temporaries_on_signal();
  // Allocations past the memory limit fail (std::bad_alloc, one line below) instead of the
  // kernel killing the process; a command's --memory-limit sets its own.
  cli::apply_memory_limit(cli::default_memory_limit());
  try {
    return run(*command, words);
  } catch (const cli::UsageError& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", name.c_str(), knnocc::io::printable(e.what()).c_str());
  } catch (const knnocc::io::Error& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", name.c_str(), e.what());
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr,
                 "knnocc %s: out of memory: the command needs more than the memory limit of %s "
                 "(--memory-limit SIZE raises it; default 80 %% of this machine's memory)\n",
                 name.c_str(), cli::format_bytes(cli::memory_limit_bytes()).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "knnocc %s: %s\n", name.c_str(), knnocc::io::printable(e.what()).c_str());
  }
  return 2;
}
